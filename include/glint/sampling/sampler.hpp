// glint/sampling/sampler.hpp: the Sampler concept (a source of sample dimensions for one
// pixel sample at a time) and its independent-random baseline, RandomSampler.
//
// A renderer asks a sampler for the sample of pixel (x, y) with number i, then draws its
// dimensions in order: get_pixel_2d() for the position inside the pixel, then get_1d() /
// get_2d() for everything else (lens, lights, BRDF lobes, roulette). HaltonSampler
// (halton.hpp) is the low-discrepancy policy; RandomSampler is what it is compared against.
#pragma once

#include <concepts>
#include <cstdint>

#include <glint/core/math.hpp>
#include <glint/core/random.hpp>

namespace glint {

/// What a path tracer needs from a sample generator.
template <class S, class T>
concept Sampler = Scalar<T> && requires(S s, int x, int y, std::uint64_t i) {
    s.start_pixel_sample(x, y, i);
    { s.get_1d() } -> std::same_as<T>;
    { s.get_2d() } -> std::same_as<Vec2<T>>;
    { s.get_pixel_2d() } -> std::same_as<Vec2<T>>;
};

/// Independent uniform samples from PCG32; the stream of pixel sample (x, y, i) depends only on
/// (seed, x, y, i), hashed (Pcg32::hashed), so results do not depend on the order pixels are
/// rendered in and neighbouring pixels, samples or seeds give independent streams.
template <Scalar T>
class RandomSampler {
public:
    /// A sampler whose streams are all keyed by `seed`; different seeds give independent images.
    explicit RandomSampler(std::uint64_t seed = 0) : seed_(seed) {}

    /// Begin sample `index` of pixel (x, y): restarts the stream at the hash of (seed, x, y,
    /// index). Call before drawing any dimension of the sample.
    void start_pixel_sample(int x, int y, std::uint64_t index) {
        const std::uint64_t pixel =
            (std::uint64_t(std::uint32_t(x)) << 32) | std::uint64_t(std::uint32_t(y));
        rng_ = Pcg32::hashed(index ^ detail::mix_bits(seed_), pixel);
    }
    /// Next uniform number in [0, 1) of the current pixel sample.
    [[gnu::always_inline]] T get_1d() { return rng_.uniform<T>(); }
    /// Next two uniform numbers in [0, 1), drawn in order (x first).
    [[gnu::always_inline]] Vec2<T> get_2d() {
        const T a = rng_.uniform<T>();
        return Vec2<T>(a, rng_.uniform<T>());
    }
    /// Position inside the pixel in [0, 1)^2; for this sampler simply the next get_2d().
    Vec2<T> get_pixel_2d() { return get_2d(); }

private:
    std::uint64_t seed_;
    Pcg32 rng_;
};

}  // namespace glint
