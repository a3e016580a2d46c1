// glint/sampling/halton.hpp: Halton and Hammersley point sets with optional randomization,
// and HaltonSampler, the per-pixel enumeration of one global Halton sequence.
//
// Larsen 2004, §6: dimension k of a Halton point i is the radical inverse
// Phi_{p_k}(i) in the k-th prime base (6.1, 6.2); Szirmay-Kalos 1998, §4.1: quasi-Monte
// Carlo walks draw their directions from Halton (unknown count) or Hammersley (known count N:
// point i is (i/N, Phi_2(i), Phi_3(i), ...)) sequences. Larsen 2004, §6.1 mentions that a plain
// Halton sequence "is far from random" and can be scrambled; glint offers:
//   none               plain radical inverse;
//   cranley_patterson  a random shift per dimension, added modulo 1 (on the exact 64-bit
//                      fraction, so the wrap-around is exact);
//   digit_permutation  one random permutation of the base-b digits per digit position;
//   owen               Owen's nested uniform scrambling (a permutation per digit-tree node).
// The three randomizations make every point uniformly distributed, so estimators built on them
// are unbiased and their error can be measured over independent seeds.
//
// HaltonSampler follows pbrt-v4's HaltonSampler (Pharr, Jakob, Humphreys, 4th ed., 8.6): the
// first two dimensions, scaled by 2^e0 >= min(width, R) and 3^e1 >= min(height, R), place a
// global Halton point in pixel (x mod R, y mod R) exactly when its index is congruent to the
// inverse radical inverses of x and y modulo 2^e0 and 3^e1; the Chinese remainder theorem gives
// the first such index and every further sample of the pixel is 2^e0 3^e1 indices later. An
// image rendered this way is a single low-discrepancy point set (tiled with period R pixels).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/sampling/permuted_radical_inverse.hpp>
#include <glint/sampling/primes.hpp>
#include <glint/sampling/radical_inverse.hpp>
#include <glint/sampling/sampler.hpp>

namespace glint {

/// How a Halton sequence is randomized (see the header comment): not at all, by a random shift
/// per dimension, by random digit permutations, or by Owen's nested scrambling.
enum class HaltonRandomization { none, cranley_patterson, digit_permutation, owen };

/// Name used in benchmark output ("none", "cp", "perm", "owen").
constexpr const char* short_name(HaltonRandomization r) {
    switch (r) {
        case HaltonRandomization::none: return "none";
        case HaltonRandomization::cranley_patterson: return "cp";
        case HaltonRandomization::digit_permutation: return "perm";
        case HaltonRandomization::owen: return "owen";
    }
    return "?";
}

/// A (randomized) Halton sequence in up to prime_count dimensions. Construction draws the
/// randomization from Pcg32(seed) and may allocate; sample() does neither allocate nor throw.
/// Copies share the (immutable) randomization tables.
template <Scalar T>
class Halton {
public:
    /// The first `dims` prime bases (dims in [1, prime_count]), randomized as `randomization`
    /// asks with tables drawn from Pcg32(seed). Throws Error for dims outside that range.
    explicit Halton(std::size_t dims, HaltonRandomization randomization = HaltonRandomization::none,
                    std::uint64_t seed = 0) {
        if (dims == 0 || dims > prime_count)
            throw Error("glint::Halton: dimension count " + std::to_string(dims) +
                        " outside [1, " + std::to_string(prime_count) + "] (one prime base each)");
        auto data = std::make_shared<Data>();
        Data& d = *data;
        d.dims = dims;
        d.randomization = randomization;
        Pcg32 rng(seed, 0x68616c746f6eULL);  // "halton"
        switch (randomization) {
            case HaltonRandomization::none: break;
            case HaltonRandomization::cranley_patterson:
                d.keys.resize(dims);
                for (auto& k : d.keys) k = rng.next_u64();
                break;
            case HaltonRandomization::owen:
                d.keys.resize(dims);
                d.digits.resize(dims);
                for (std::size_t k = 0; k < dims; ++k) {
                    d.keys[k] = rng.next_u64();
                    d.digits[k] = scrambled_digit_count(primes[k]);
                }
                break;
            case HaltonRandomization::digit_permutation: {
                d.digits.resize(dims);
                d.offsets.resize(dims);
                std::size_t total = 0;
                for (std::size_t k = 0; k < dims; ++k) {
                    d.digits[k] = scrambled_digit_count(primes[k]);
                    d.offsets[k] = total;
                    total += std::size_t(d.digits[k]) * primes[k];
                }
                d.perms.resize(total);
                d.tails.resize(dims * 65);
                for (std::size_t k = 0; k < dims; ++k) {
                    const std::uint32_t b = primes[k];
                    for (int j = 0; j < d.digits[k]; ++j) {
                        std::uint16_t* p = d.perms.data() + d.offsets[k] + std::size_t(j) * b;
                        for (std::uint32_t i = 0; i < b; ++i) p[i] = static_cast<std::uint16_t>(i);
                        for (std::uint32_t i = b - 1; i > 0; --i) {  // Fisher-Yates
                            const std::uint32_t r = rng.bounded(i + 1);
                            const std::uint16_t t = p[i];
                            p[i] = p[r];
                            p[r] = t;
                        }
                    }
                    permuted_digit_tails(b, d.perms.data() + d.offsets[k], d.digits[k],
                                         d.tails.data() + k * 65);
                }
                break;
            }
        }
        data_ = std::move(data);
    }

    /// Number of dimensions (prime bases 2, 3, 5, ...).
    std::size_t dims() const { return data_->dims; }
    /// The randomization chosen at construction.
    HaltonRandomization randomization() const { return data_->randomization; }

    /// Coordinate `dim` (< dims()) of point `index` as an exact 64-bit fraction.
    std::uint64_t sample_bits(std::uint64_t index, std::size_t dim) const {
        const Data& d = *data_;
        const std::uint32_t base = primes[dim];
        switch (d.randomization) {
            case HaltonRandomization::none: return radical_inverse_bits(base, index);
            case HaltonRandomization::cranley_patterson:
                return radical_inverse_bits(base, index) + d.keys[dim];  // wraps modulo 1
            case HaltonRandomization::digit_permutation:
                return permuted_radical_inverse_bits(base, index, d.perms.data() + d.offsets[dim],
                                                     d.tails.data() + dim * 65, d.digits[dim]);
            case HaltonRandomization::owen:
                return owen_scrambled_radical_inverse_bits(base, index, d.keys[dim], d.digits[dim]);
        }
        return 0;
    }

    /// Coordinate `dim` (< dims()) of point `index`, in [0, 1).
    T sample(std::uint64_t index, std::size_t dim) const {
        return fraction_to_unit<T>(sample_bits(index, dim));
    }

private:
    struct Data {
        std::size_t dims = 0;
        HaltonRandomization randomization = HaltonRandomization::none;
        std::vector<std::uint64_t> keys;    // CP shifts or Owen seeds, per dimension
        std::vector<int> digits;            // scrambled digit count per dimension
        std::vector<std::size_t> offsets;   // start of each dimension's permutations
        std::vector<std::uint16_t> perms;   // [dim][digit position][digit]
        std::vector<std::uint64_t> tails;   // [dim][65]: permuted_digit_tails
    };
    std::shared_ptr<const Data> data_;
};

/// Hammersley point set of a known size N: coordinate 0 of point i is i/N, coordinate k >= 1 is
/// the (randomized) Halton coordinate k-1. A Cranley-Patterson randomization also shifts
/// coordinate 0.
template <Scalar T>
class Hammersley {
public:
    /// `count` points in `dims` dimensions; coordinates 1 .. dims-1 use Halton<T>(dims - 1,
    /// randomization, seed). Throws Error when count or dims is 0, or dims - 1 > prime_count.
    Hammersley(std::uint64_t count, std::size_t dims,
               HaltonRandomization randomization = HaltonRandomization::none,
               std::uint64_t seed = 0)
        : count_(count), halton_(dims > 1 ? dims - 1 : 1, randomization, seed) {
        if (count == 0) throw Error("glint::Hammersley: the point count must be positive");
        if (dims == 0) throw Error("glint::Hammersley: the dimension count must be positive");
        if (randomization == HaltonRandomization::cranley_patterson)
            shift0_ = Pcg32(seed, 0x68616d6dULL).next_u64();
    }

    /// Number of points N in the set (coordinate 0 of point i is i/N).
    std::uint64_t count() const { return count_; }

    /// Coordinate `dim` of point `index` (< count()), in [0, 1).
    T sample(std::uint64_t index, std::size_t dim) const {
        if (dim == 0) return fraction_to_unit<T>(detail::floor_fraction(index, count_) + shift0_);
        return halton_.sample(index, dim - 1);
    }

private:
    std::uint64_t count_;
    Halton<T> halton_;
    std::uint64_t shift0_ = 0;
};

namespace detail {

/// x^-1 modulo n (gcd(x, n) = 1), by the extended Euclidean algorithm.
constexpr std::uint64_t multiplicative_inverse(std::int64_t x, std::int64_t n) {
    std::int64_t r0 = n, r1 = x % n, t0 = 0, t1 = 1;
    while (r1 != 0) {
        const std::int64_t q = r0 / r1;
        const std::int64_t r2 = r0 - q * r1, t2 = t0 - q * t1;
        r0 = r1;
        r1 = r2;
        t0 = t1;
        t1 = t2;
    }
    return static_cast<std::uint64_t>(((t0 % n) + n) % n);
}

}  // namespace detail

/// The Halton dimensions glint's renderers draw per sample (the pixel and the first two
/// vertices of a walk); PCG numbers after them (HaltonSampler's dimension policy).
inline constexpr std::size_t render_halton_dims = 18;

/// Per-pixel enumeration of one global (randomized) Halton sequence; satisfies Sampler<T>.
///
/// Dimension policy. Dimensions 0 and 1 (bases 2 and 3) place the point in the image and are
/// never randomized (that would break the enumeration). Dimensions 2 .. dims-1 are Halton
/// dimensions randomized as asked: `digit_permutation` (and `none`) by the tables of
/// PermutedRadicalInverse (permuted_radical_inverse.hpp, the fast path), `cranley_patterson`
/// and `owen` by Halton<T>. A walk that asks for more than `dims` dimensions continues with
/// independent uniform numbers from a PCG32 stream seeded by (seed, pixel, sample index),
/// like RandomSampler: no number is ever reused, so estimators stay unbiased however long
/// the walk (high Halton dimensions converge like random numbers anyway, see docs/sampling.md).
template <Scalar T>
class HaltonSampler {
public:
    /// A sampler for a width x height image (tiled every max_resolution pixels, in [1, 4096])
    /// drawing `dims` Halton dimensions (in [3, prime_count], the pixel's two included), randomized
    /// as asked with tables from `seed`. Allocates its tables; throws Error on a bad argument.
    HaltonSampler(int width, int height, std::size_t dims,
                  HaltonRandomization randomization = HaltonRandomization::none,
                  std::uint64_t seed = 0, int max_resolution = 128)
        : randomization_(randomization), dims_(dims), seed_(seed) {
        if (width <= 0 || height <= 0)
            throw Error("glint::HaltonSampler: image size " + std::to_string(width) + "x" +
                        std::to_string(height) + " must be positive");
        if (dims < 3 || dims > prime_count)
            throw Error("glint::HaltonSampler: dimension count " + std::to_string(dims) + " outside [3, " +
                        std::to_string(prime_count) + "] (2 for the pixel, one prime base each)");
        if (max_resolution <= 0 || max_resolution > 4096)
            throw Error("glint::HaltonSampler: max_resolution must be in [1, 4096]");
        max_resolution_ = max_resolution;
        const bool table = randomization == HaltonRandomization::none ||
                           randomization == HaltonRandomization::digit_permutation;
        table_ = std::make_shared<const PermutedRadicalInverse<T>>(
            table ? dims : 2, seed, randomization == HaltonRandomization::none ? dims : 2);
        if (!table) halton_ = std::make_shared<const Halton<T>>(dims, randomization, seed);
        const int res[2] = {width, height};
        for (int i = 0; i < 2; ++i) {
            const std::uint64_t base = primes[std::size_t(i)];
            std::uint64_t scale = 1;
            int exponent = 0;
            while (scale < std::uint64_t(std::min(res[i], max_resolution))) {
                scale *= base;
                ++exponent;
            }
            scales_[i] = scale;
            exponents_[i] = exponent;
        }
        scale_y_ = InvariantDivisor(std::uint32_t(scales_[1]));
        stride_ = scales_[0] * scales_[1];
        inverses_[0] = detail::multiplicative_inverse(std::int64_t(scales_[1]), std::int64_t(scales_[0]));
        inverses_[1] = detail::multiplicative_inverse(std::int64_t(scales_[0]), std::int64_t(scales_[1]));
    }

    /// Number of dimensions drawn from the Halton sequence (the pixel's two included).
    std::size_t dims() const { return dims_; }
    /// The randomization of dimensions 2 .. dims()-1 (dimensions 0 and 1 are never randomized).
    HaltonRandomization randomization() const { return randomization_; }
    /// Number of consecutive global indices that visit every pixel (of a max_resolution tile)
    /// exactly once: 2^e0 * 3^e1.
    std::uint64_t stride() const { return stride_; }
    /// Pixel-coordinate scales 2^e0 and 3^e1.
    std::uint64_t scale(int axis) const { return scales_[axis]; }

    /// Index in the global sequence of sample `sample_index` of pixel (x, y).
    std::uint64_t global_index(int x, int y, std::uint64_t sample_index) const {
        return pixel_first_index(x, y) + sample_index * stride_;
    }

    /// Position inside its pixel of global point `index`: the fractional parts of
    /// Phi_2(index) * 2^e0 and Phi_3(index) * 3^e1.
    Vec2<T> pixel_offset(std::uint64_t index) const {
        return Vec2<T>(radical_inverse<T>(2, index >> exponents_[0]), (*table_)(1, scale_y_.quotient(index)));
    }

    /// Halton dimension `dim` (2 <= dim < dims()) of global point `index`.
    T sample(std::uint64_t index, std::size_t dim) const {
        if (dim < 2 || dim >= dims_)
            throw Error("glint::HaltonSampler::sample: dimension " + std::to_string(dim) + " outside [2, " +
                        std::to_string(dims_) + ")");
        return halton_dimension(index, dim);
    }

    // Sampler interface.
    /// Begin sample `sample_index` of pixel (x, y) (any integers; taken modulo max_resolution):
    /// selects its global index and restarts at dimension 2. Cheap when the pixel repeats.
    void start_pixel_sample(int x, int y, std::uint64_t sample_index) {
        if (x != cached_x_ || y != cached_y_) {  // a pixel's samples come one after another
            cached_first_ = pixel_first_index(x, y);
            cached_x_ = x;
            cached_y_ = y;
        }
        index_ = cached_first_ + sample_index * stride_;
        sample_index_ = sample_index;
        dim_ = 2;
        tail_started_ = false;
    }
    /// Position in [0, 1)^2 inside the pixel of the current sample (Halton dimensions 0 and 1);
    /// does not advance the dimension.
    Vec2<T> get_pixel_2d() const { return pixel_offset(index_); }
    /// Next dimension of the current sample in [0, 1): Halton while dimensions last, then PCG32.
    T get_1d() { return dim_ < dims_ ? halton_dimension(index_, dim_++) : tail(); }
    /// Next two dimensions of the current sample, in order (two get_1d() calls).
    Vec2<T> get_2d() {
        const T a = get_1d();
        return Vec2<T>(a, get_1d());
    }

private:
    T halton_dimension(std::uint64_t index, std::size_t dim) const {
        return halton_ ? halton_->sample(index, dim) : (*table_)(dim, index);
    }

    /// Past the last Halton dimension: PCG32 seeded by (seed, pixel, sample index).
    T tail() {
        if (!tail_started_) {
            const std::uint64_t pixel =
                (std::uint64_t(std::uint32_t(cached_x_)) << 32) | std::uint64_t(std::uint32_t(cached_y_));
            tail_ = Pcg32::hashed(sample_index_ ^ detail::mix_bits(seed_ ^ 0x68616c746f6e7461ULL), pixel);
            tail_started_ = true;
        }
        return tail_.uniform<T>();
    }

    /// The first global index inside pixel (x, y): congruent to the inverse radical inverses of
    /// x and y modulo 2^e0 and 3^e1 (Chinese remainder theorem).
    std::uint64_t pixel_first_index(int x, int y) const {
        if (stride_ <= 1) return 0;
        const int m = max_resolution_;
        const std::uint64_t pm[2] = {std::uint64_t(((x % m) + m) % m), std::uint64_t(((y % m) + m) % m)};
        std::uint64_t index = 0;
        for (int i = 0; i < 2; ++i) {
            const std::uint64_t offset = inverse_radical_inverse(pm[i], primes[std::size_t(i)], exponents_[i]);
            index += offset * (stride_ / scales_[i]) * inverses_[i];
        }
        return index % stride_;
    }

    HaltonRandomization randomization_;
    std::size_t dims_;
    std::uint64_t seed_;
    std::shared_ptr<const PermutedRadicalInverse<T>> table_;  // dims 0, 1 (and the rest if used)
    std::shared_ptr<const Halton<T>> halton_;                 // cranley_patterson and owen only
    int max_resolution_ = 128;
    std::uint64_t scales_[2] = {1, 1};
    int exponents_[2] = {0, 0};
    InvariantDivisor scale_y_;
    std::uint64_t inverses_[2] = {0, 0};
    std::uint64_t stride_ = 1;
    // Current pixel sample.
    std::uint64_t index_ = 0, sample_index_ = 0, cached_first_ = 0;
    std::size_t dim_ = 2;
    int cached_x_ = std::numeric_limits<int>::min(), cached_y_ = 0;
    bool tail_started_ = false;
    Pcg32 tail_;
};

}  // namespace glint
