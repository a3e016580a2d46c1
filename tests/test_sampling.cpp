// Tests for glint/sampling: exact radical-inverse values, Halton/Hammersley structure, warps and
// their densities, Russian roulette and BRDF selection, multiple correlated sampling.
// Statistical cases use fixed seeds and tolerances computed from the measured sample variance
// (|mean - exact| < 4 standard errors), never hand-tuned constants.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <set>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/sampling/correlated.hpp>
#include <glint/sampling/halton.hpp>
#include <glint/sampling/permuted_radical_inverse.hpp>
#include <glint/sampling/primes.hpp>
#include <glint/sampling/radical_inverse.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/brdf.hpp>

using namespace glint;

namespace {

/// Running mean and variance (Welford) of a scalar estimator.
struct Stats {
    double n = 0, mean = 0, m2 = 0;
    void add(double x) {
        n += 1;
        const double d = x - mean;
        mean += d / n;
        m2 += d * (x - mean);
    }
    double variance() const { return n > 1 ? m2 / (n - 1) : 0; }
    double stderr_mean() const { return std::sqrt(variance() / n); }
    /// Standard error of variance(): sqrt((m4 - s^4)/n) needs the fourth moment; we keep it.
};

/// Mean, variance and the standard error of the variance (from the fourth central moment).
struct MomentStats {
    std::vector<double> xs;
    void add(double x) { xs.push_back(x); }
    double mean() const {
        double s = 0;
        for (double x : xs) s += x;
        return s / double(xs.size());
    }
    double variance() const {
        const double m = mean();
        double s = 0;
        for (double x : xs) s += (x - m) * (x - m);
        return s / double(xs.size() - 1);
    }
    double variance_stderr() const {
        const double m = mean(), v = variance();
        double m4 = 0;
        for (double x : xs) m4 += std::pow(x - m, 4);
        m4 /= double(xs.size());
        return std::sqrt(std::max(0.0, m4 - v * v) / double(xs.size()));
    }
};

/// Check the mean of n draws of `estimator` is within 4 standard errors of `exact`.
template <class F>
void check_unbiased(F&& estimator, double exact, int n) {
    Stats s;
    for (int i = 0; i < n; ++i) s.add(estimator());
    INFO("mean " << s.mean << " exact " << exact << " stderr " << s.stderr_mean());
    CHECK(std::abs(s.mean - exact) <= 4 * s.stderr_mean());  // <=: a zero integrand is exact
}

/// Is `r` the largest double not above p/q?  Exact integer comparison r = k / 2^53.
bool is_floor_of_ratio(double r, std::uint64_t p, std::uint64_t q) {
    const auto k = static_cast<std::uint64_t>(std::ldexp(r, 53));
    if (std::ldexp(double(k), -53) != r) return false;
    using u128 = detail::u128;
    const u128 lhs = u128(k) * q, rhs = u128(p) << 53;
    return lhs <= rhs && (u128(k) + 1) * q > rhs;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Radical inverse and Halton
// ---------------------------------------------------------------------------------------------

TEST_CASE("exact: radical inverse check values of 003 section 6 (eq. 6.2)") {
    // Phi_10(1234) = 0.4321, Phi_10(524) = 0.425, Phi_10(2) = 0.2, Phi_10(23) = 0.32, each the
    // largest double not above the exact decimal.
    CHECK(is_floor_of_ratio(radical_inverse<double>(10, 1234), 4321, 10000));
    CHECK(is_floor_of_ratio(radical_inverse<double>(10, 524), 425, 1000));
    CHECK(is_floor_of_ratio(radical_inverse<double>(10, 2), 2, 10));
    CHECK(is_floor_of_ratio(radical_inverse<double>(10, 23), 32, 100));
    CHECK(radical_inverse<float>(10, 1234) <= 0.4321f);
    CHECK(std::nextafter(radical_inverse<float>(10, 1234), 1.0f) > 0.4321);
    // Base 2, eq. 6.2: {0, 1/2, 1/4, 3/4, 1/8, 3/8, 5/8, 7/8, 1/16, 3/16, 5/16, ...}. The thesis
    // lists each level (indices b^k .. b^(k+1)-1) sorted; in index order level 3 is
    // 1/8, 5/8, 3/8, 7/8. Checked: the exact sequence, and each level as a set.
    const double base2[] = {0,     0.5,   0.25,   0.75,   0.125,  0.625,  0.375, 0.875,
                            0.0625, 0.5625, 0.3125, 0.8125, 0.1875, 0.6875, 0.4375, 0.9375};
    for (std::uint64_t i = 0; i < std::size(base2); ++i) {
        CHECK(radical_inverse<double>(2, i) == base2[i]);
        CHECK(radical_inverse<float>(2, i) == float(base2[i]));
    }
    for (std::uint64_t level = 1; level < 10; ++level) {
        std::set<double> got, want;
        for (std::uint64_t i = std::uint64_t(1) << (level - 1); i < (std::uint64_t(1) << level); ++i) {
            got.insert(radical_inverse<double>(2, i));
            want.insert(double(2 * (i - (std::uint64_t(1) << (level - 1))) + 1) /
                        double(std::uint64_t(1) << level));
        }
        CHECK(got == want);
    }
    // Base 3: 0, 1/3, 2/3, 1/9, 4/9, 7/9, 2/9 (rounded down).
    const std::uint64_t num3[] = {0, 1, 2, 1, 4, 7, 2}, den3[] = {1, 3, 3, 9, 9, 9, 9};
    for (std::uint64_t i = 0; i < 7; ++i)
        CHECK(is_floor_of_ratio(radical_inverse<double>(3, i), num3[i], den3[i]));
}

TEST_CASE("exact: radical inverse agrees with a rational reference for the first 1000 primes") {
    Pcg32 rng(11);
    for (std::size_t k = 0; k < 1000; ++k) {
        const std::uint32_t b = primes[k];
        for (int t = 0; t < 20; ++t) {
            // Indices below 2^40 so that the reference's b^digits fits in 64 bits... or not:
            // the reference builds p/q in 128 bits and compares exactly.
            const std::uint64_t i = rng.next_u64() >> (24 + rng.bounded(40));
            detail::u128 p = 0, q = 1;
            for (std::uint64_t j = i; j; j /= b) {
                p = p * b + j % b;
                q *= b;
            }
            const double r = radical_inverse<double>(b, i);
            REQUIRE(r < 1.0);
            const auto kk = static_cast<std::uint64_t>(std::ldexp(r, 53));
            // floor: k/2^53 <= p/q < (k+1)/2^53  <=>  k q <= p 2^53 < (k+1) q
            REQUIRE(q < (detail::u128(1) << 74));
            CHECK(detail::u128(kk) * q <= (p << 53));
            CHECK((detail::u128(kk) + 1) * q > (p << 53));
        }
    }
}

TEST_CASE("stress: radical inverse of 64-bit indices stays strictly below 1") {
    const std::uint64_t big[] = {~std::uint64_t(0), ~std::uint64_t(0) - 1, std::uint64_t(1) << 63,
                                 0x123456789abcdef0ULL};
    for (std::size_t k : {std::size_t(0), std::size_t(1), std::size_t(5), std::size_t(999),
                          std::size_t(1023)}) {
        for (std::uint64_t i : big) {
            const float f = radical_inverse<float>(primes[k], i);
            const double d = radical_inverse<double>(primes[k], i);
            CHECK(f >= 0.0f);
            CHECK(f < 1.0f);
            CHECK(d >= 0.0);
            CHECK(d < 1.0);
            CHECK(double(f) <= d);
        }
    }
    // The all-ones base-2 index maps to the largest value below 1.
    CHECK(radical_inverse<double>(2, ~std::uint64_t(0)) == std::nextafter(1.0, 0.0));
    CHECK(radical_inverse<float>(2, ~std::uint64_t(0)) == std::nextafter(1.0f, 0.0f));
}

TEST_CASE("exact: prime table and inverse radical inverse") {
    CHECK(primes[0] == 2);
    CHECK(primes[9] == 29);
    CHECK(primes[999] == 7919);
    for (std::size_t k = 1; k < prime_count; ++k) {
        REQUIRE(primes[k] > primes[k - 1]);
        for (std::uint32_t d = 2; d * d <= primes[k]; ++d) REQUIRE(primes[k] % d != 0);
    }
    for (std::uint32_t b : {2u, 3u, 5u, 7919u}) {
        for (std::uint64_t i = 0; i < 200; ++i) {
            const int digits = 3;
            std::uint64_t bd = 1;
            for (int j = 0; j < digits; ++j) bd *= b;
            const std::uint64_t rev = radical_inverse_bits(b, i % bd);
            // Phi_b(i mod b^3) * b^3 is an integer: the reversed digits.
            const auto reversed = static_cast<std::uint64_t>(
                (detail::u128(rev) * bd + (detail::u128(1) << 63)) >> 64);
            CHECK(inverse_radical_inverse(reversed, b, digits) == i % bd);
        }
    }
}

TEST_CASE("exact: digit scramblings are bijections on digits and keep stratification") {
    // Kensler's permutation is a bijection for every length.
    for (std::uint32_t n : {2u, 3u, 5u, 7u, 31u, 100u, 7919u}) {
        std::vector<bool> seen(n, false);
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::uint32_t p = detail::permutation_element(i, n, 0x9e3779b9u * n);
            REQUIRE(p < n);
            CHECK_FALSE(seen[p]);
            seen[p] = true;
        }
    }
    // Each randomization keeps the first b^2 points of dimension k in distinct 1/b^2 strata
    // (the van der Corput net property), for several bases.
    for (auto r : {HaltonRandomization::none, HaltonRandomization::cranley_patterson,
                   HaltonRandomization::digit_permutation, HaltonRandomization::owen}) {
        Halton<double> h(8, r, 42);
        for (std::size_t dim : {std::size_t(0), std::size_t(1), std::size_t(4), std::size_t(7)}) {
            const std::uint64_t b = primes[dim], n = b * b;
            std::vector<int> count(n, 0);
            for (std::uint64_t i = 0; i < n; ++i) {
                const double x = h.sample(i, dim);
                REQUIRE(x >= 0.0);
                REQUIRE(x < 1.0);
                // Cranley-Patterson shifts the strata: count modulo the shift (and centre on the
                // stratum). Values are rounded down, so an exact k/n may read as k/n - ulp:
                // nudge by 2^-40, far below a stratum's width.
                double y = x + 1.0 + 0x1p-40;
                if (r == HaltonRandomization::cranley_patterson)
                    y += 0.5 / double(n) - h.sample(0, dim);
                count[std::size_t(y * double(n)) % n]++;
            }
            INFO("randomization " << std::string(short_name(r)) << " dim " << dim);
            CHECK(std::all_of(count.begin(), count.end(), [](int c) { return c == 1; }));
        }
    }
}

TEST_CASE("statistics: randomized Halton points are uniform (unbiased integration)") {
    // The mean of x^2 over the first 64 points, over independent seeds, has expectation 1/3
    // for every randomization.
    for (auto r : {HaltonRandomization::cranley_patterson, HaltonRandomization::digit_permutation,
                   HaltonRandomization::owen}) {
        for (std::size_t dim : {std::size_t(0), std::size_t(3), std::size_t(20)}) {
            std::uint64_t seed = 1;
            INFO("randomization " << std::string(short_name(r)) << " dim " << dim);
            check_unbiased(
                [&] {
                    Halton<double> h(21, r, seed++);
                    double s = 0;
                    for (std::uint64_t i = 0; i < 7; ++i) s += std::pow(h.sample(i, dim), 2);
                    return s / 7;
                },
                1.0 / 3.0, 2000);
        }
    }
}

TEST_CASE("exact: Hammersley set of N points has first coordinate i/N") {
    Hammersley<double> h(1000, 3);
    for (std::uint64_t i = 0; i < 1000; ++i) {
        CHECK(is_floor_of_ratio(h.sample(i, 0), i, 1000));
        CHECK(h.sample(i, 1) == radical_inverse<double>(2, i));
        CHECK(h.sample(i, 2) == radical_inverse<double>(3, i));
    }
    CHECK_THROWS_AS(Hammersley<double>(0, 2), Error);
}

TEST_CASE("exact: HaltonSampler enumerates exactly the global points inside each pixel") {
    for (auto [w, h] : {std::pair{8, 6}, std::pair{5, 7}, std::pair{130, 3}}) {
        for (auto r : {HaltonRandomization::owen, HaltonRandomization::digit_permutation}) {
            HaltonSampler<double> sampler(w, h, 6, r, 3);
            const std::uint64_t stride = sampler.stride();
            const std::uint64_t sx = sampler.scale(0), sy = sampler.scale(1);
            CHECK(sx >= std::uint64_t(std::min(w, 128)));
            CHECK(sy >= std::uint64_t(std::min(h, 128)));
            std::set<std::uint64_t> indices;
            for (int y = 0; y < int(sy); ++y) {
                for (int x = 0; x < int(sx); ++x) {
                    for (std::uint64_t s = 0; s < 3; ++s) {
                        const std::uint64_t g = sampler.global_index(x, y, s);
                        indices.insert(g);
                        // The global point, scaled to the image, lies in pixel (x, y) ...
                        // (Phi is rounded down: an exact k/3 reads k/3 - ulp, hence the nudge.)
                        const double gx = radical_inverse<double>(2, g) * double(sx) + 0x1p-40;
                        const double gy = radical_inverse<double>(3, g) * double(sy) + 0x1p-40;
                        REQUIRE(int(gx) == x);
                        REQUIRE(int(gy) == y);
                        // ... at the offset the sampler reports.
                        const Vec2<double> o = sampler.pixel_offset(g);
                        CHECK(std::abs(gx - x - o.x) < 1e-9);
                        CHECK(std::abs(gy - y - o.y) < 1e-9);
                        CHECK(o.x < 1.0);
                        CHECK(o.y < 1.0);
                    }
                }
            }
            // Three samples per pixel use exactly the first 3 * stride points of the sequence.
            CHECK(indices.size() == 3 * stride);
            CHECK(*indices.rbegin() == 3 * stride - 1);
        }
    }
    // Sampler interface: dimensions 2 .. dims-1 are the randomized Halton dimensions.
    static_assert(Sampler<HaltonSampler<float>, float>);
    static_assert(Sampler<RandomSampler<float>, float>);
    for (auto r : {HaltonRandomization::cranley_patterson, HaltonRandomization::digit_permutation}) {
        HaltonSampler<float> s(16, 16, 4, r, 9);
        s.start_pixel_sample(3, 5, 2);
        const std::uint64_t g = s.global_index(3, 5, 2);
        CHECK(s.get_1d() == s.sample(g, 2));
        CHECK(s.get_1d() == s.sample(g, 3));
        CHECK_THROWS_AS(s.sample(g, 4), Error);  // past the last Halton dimension
    }
    CHECK_THROWS_AS(HaltonSampler<float>(0, 4, 4), Error);
    CHECK_THROWS_AS(HaltonSampler<float>(4, 4, 2), Error);
    CHECK_THROWS_AS(Halton<float>(prime_count + 1), Error);
    CHECK_THROWS_AS(Halton<float>(0), Error);
}

namespace {

/// R = sum_j pi_j(a_j) b^(n-1-j) digit by digit with plain division (the reference the table
/// lookups of PermutedRadicalInverse must equal).
template <class T>
detail::u128 reference_reversed_digits(const PermutedRadicalInverse<T>& p, std::size_t dim, std::uint64_t index) {
    const std::uint32_t b = p.base(dim);
    const int n = p.digits(dim);
    detail::u128 reversed = 0;
    for (int j = 0; j < n; ++j) {
        reversed = reversed * b + p.permutation(dim, j, std::uint32_t(index % b));
        index /= b;
    }
    return reversed;
}

detail::u128 power(std::uint32_t b, int n) {
    detail::u128 p = 1;
    for (int i = 0; i < n; ++i) p *= b;
    return p;
}

template <class T>
void check_permuted_radical_inverse(std::uint32_t max_group_base, std::size_t identity_dims) {
    const std::size_t dims = 120;
    const PermutedRadicalInverse<T> p(dims, 77, identity_dims, max_group_base);
    Pcg32 rng(5, 6);
    for (std::size_t dim = 0; dim < dims; ++dim) {
        const std::uint32_t b = p.base(dim);
        const int n = p.digits(dim);
        INFO("T digits " << std::numeric_limits<T>::digits << " dim " << dim << " base " << b
                         << " digits " << n << " max group base " << max_group_base);
        REQUIRE(b == primes[dim]);
        // Enough digits for T's precision unless b^n would reach 2^64.
        CHECK(power(b, n) < (detail::u128(1) << 64));
        CHECK((power(b, n) >= (detail::u128(1) << std::numeric_limits<T>::digits) ||
               n == scrambled_digit_count(b)));
        // Each digit position's map is a permutation (the identity below identity_dims).
        for (int j = 0; j < n; ++j) {
            std::vector<int> seen(b, 0);
            bool identity = true;
            for (std::uint32_t a = 0; a < b; ++a) {
                const std::uint32_t v = p.permutation(dim, j, a);
                REQUIRE(v < b);
                seen[v]++;
                identity = identity && v == a;
            }
            CHECK(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; }));
            if (dim < identity_dims) CHECK(identity);
        }
        CHECK(p.offset(dim) >= 0.0);
        CHECK(p.offset(dim) < 1.0);
        if (dim < identity_dims) CHECK(p.offset(dim) == 0.0);
        // Table lookups equal the digit-by-digit reference; the value is (R + u) / b^n.
        const long double bn = static_cast<long double>(power(b, n));
        for (int t = 0; t < 300; ++t) {
            const std::uint64_t index = t < 200 ? std::uint64_t(t) : t < 250 ? rng.next_u64() : ~std::uint64_t(t - 250);
            const std::uint64_t r = p.reversed_digits(dim, index);
            REQUIRE(detail::u128(r) == reference_reversed_digits(p, dim, index));
            const T x = p(dim, index);
            REQUIRE(x >= T(0));
            REQUIRE(x < T(1));
            // Rounding: R to double, + u, * 1/b^n (each at most half a double ulp of a value
            // below 1, 1/b^n itself rounded), then to T (half an ulp of T).
            const long double exact = (static_cast<long double>(r) + p.offset(dim)) / bn;
            CHECK(std::abs(static_cast<long double>(x) - exact) <=
                  std::ldexp(1.0L, -std::numeric_limits<T>::digits) + std::ldexp(4.0L, -53));
        }
    }
}

}  // namespace

TEST_CASE("exact: InvariantDivisor equals integer division for 64-bit numerators") {
    Pcg32 rng(11, 12);
    std::vector<std::uint32_t> divisors = {1, 2, 3, 5, 7, 8, 625, 4096, 7919, 8161, 65536, 3u * 3u * 3u * 3u * 3u,
                                           0x80000000u, 0xffffffffu};
    for (int i = 0; i < 200; ++i) divisors.push_back(rng.next_u32() >> (rng.next_u32() % 32));
    for (std::uint32_t d : divisors) {
        if (d == 0) continue;
        const InvariantDivisor div(d);
        INFO("d " << d);
        CHECK(div.divisor() == d);
        for (std::uint64_t n : {std::uint64_t(0), std::uint64_t(d - 1), std::uint64_t(d), ~std::uint64_t(0),
                                ~std::uint64_t(0) - 1, std::uint64_t(1) << 63})
            CHECK(div.quotient(n) == n / d);
        for (int t = 0; t < 2000; ++t) {
            const std::uint64_t n = rng.next_u64() >> (t % 64);
            REQUIRE(div.quotient(n) == n / d);
            if (d > 1) REQUIRE(div.quotient32(std::uint32_t(n)) == std::uint32_t(n) / d);
        }
        if (d > 1)
            for (std::uint32_t n : {0u, d - 1, d, 0xffffffffu, 0xfffffffeu, 0x80000000u})
                CHECK(div.quotient32(n) == n / d);
    }
}

TEST_CASE("exact: permuted radical inverse equals the digit-by-digit reference") {
    // Digit groups up to 4096 (the default), 64 and 2 (one digit per table: no grouping), with
    // the pixel dimensions unpermuted or every dimension permuted, at float and double precision.
    for (std::uint32_t g : {4096u, 64u, 2u}) {
        check_permuted_radical_inverse<float>(g, 2);
        check_permuted_radical_inverse<double>(g, 0);
    }
    check_permuted_radical_inverse<double>(4096, 120);  // plain radical inverse, truncated
    CHECK(PermutedRadicalInverse<double>(3, 0, 3)(1, 1234) == doctest::Approx(radical_inverse<double>(3, 1234)).epsilon(1e-15));
    CHECK_THROWS_AS(PermutedRadicalInverse<float>(0, 1), Error);
    CHECK_THROWS_AS(PermutedRadicalInverse<float>(prime_count + 1, 1), Error);
    CHECK_THROWS_AS(PermutedRadicalInverse<float>(4, 1, 0, 70000), Error);
}

TEST_CASE("exact: permuted radical inverse keeps the first b^k points of each dimension stratified") {
    // Points 0 .. b^k - 1 of dimension `dim` fall one into each interval [i / b^k, (i+1) / b^k):
    // exactly on the integer R (its leading k digits), and on the value up to T's rounding.
    const PermutedRadicalInverse<float> p(40, 2024, 2);
    for (std::size_t dim : {std::size_t(0), std::size_t(1), std::size_t(2), std::size_t(3), std::size_t(5),
                            std::size_t(10), std::size_t(39)}) {
        const std::uint32_t b = p.base(dim);
        for (int k = 1; k <= 3 && power(b, k) <= 200000; ++k) {
            const auto count = std::uint64_t(power(b, k));
            const auto below = std::uint64_t(power(b, p.digits(dim) - k));
            std::vector<int> strata(count, 0);
            int value_misses = 0;
            for (std::uint64_t i = 0; i < count; ++i) {
                const std::uint64_t stratum = p.reversed_digits(dim, i) / below;
                REQUIRE(stratum < count);
                strata[stratum]++;
                const double x = double(p(dim, i)) * double(count);
                if (std::uint64_t(x) != stratum) ++value_misses;
                CHECK(std::abs(x - double(stratum) - 0.5) <= 0.5 + double(count) * 0x1p-24);
            }
            INFO("dim " << dim << " base " << b << " k " << k << " value rounded across a stratum edge " << value_misses);
            CHECK(std::all_of(strata.begin(), strata.end(), [](int c) { return c == 1; }));
        }
    }
}

TEST_CASE("statistics: permuted radical inverse points are uniform over seeds (unbiased)") {
    // For fixed indices, the mean over seeds of x and x^2 is 1/2 and 1/3: each point is uniform
    // on [0, 1) (random digits plus the random offset of the last digit).
    const std::size_t dims[] = {2, 3, 9, 23};
    const std::uint64_t indices[] = {0, 1, 31104 * 5 + 17};
    std::vector<Stats> stats(std::size(dims) * std::size(indices) * 2);
    for (std::uint64_t seed = 1; seed <= 1500; ++seed) {
        const PermutedRadicalInverse<float> p(24, seed, 2);
        std::size_t c = 0;
        for (std::size_t dim : dims)
            for (std::uint64_t index : indices) {
                const double x = p(dim, index);
                stats[c++].add(x);
                stats[c++].add(x * x);
            }
    }
    std::size_t c = 0;
    for (std::size_t dim : dims)
        for (std::uint64_t index : indices)
            for (int k = 1; k <= 2; ++k, ++c) {
                INFO("dim " << dim << " index " << index << " moment " << k << " mean " << stats[c].mean
                            << " stderr " << stats[c].stderr_mean());
                CHECK(std::abs(stats[c].mean - 1.0 / (k + 1)) <= 4 * stats[c].stderr_mean());
            }
}

TEST_CASE("exact: HaltonSampler past its last dimension continues with fresh numbers, never reuses") {
    // With dims = 5 the walk draws Halton dimensions 2, 3, 4, then a PCG32 stream seeded by
    // (seed, pixel, sample index): no value repeats, and the stream differs between samples.
    for (auto r : {HaltonRandomization::digit_permutation, HaltonRandomization::owen,
                   HaltonRandomization::none}) {
        HaltonSampler<float> s(16, 16, 5, r, 9);
        std::vector<float> first;
        s.start_pixel_sample(3, 5, 2);
        for (int i = 0; i < 40; ++i) first.push_back(s.get_1d());
        const std::uint64_t g = s.global_index(3, 5, 2);
        for (std::size_t d = 2; d < 5; ++d) CHECK(first[d - 2] == s.sample(g, d));
        const std::set<float> distinct(first.begin(), first.end());
        INFO("randomization " << std::string(short_name(r)));
        CHECK(distinct.size() == first.size());
        s.start_pixel_sample(3, 5, 2);  // the same sample again: the same numbers
        for (int i = 0; i < 40; ++i) CHECK(s.get_1d() == first[std::size_t(i)]);
        s.start_pixel_sample(3, 5, 3);  // the next sample: another tail
        for (int i = 0; i < 3; ++i) s.get_1d();
        int same = 0;
        for (int i = 3; i < 40; ++i) same += s.get_1d() == first[std::size_t(i)];
        CHECK(same == 0);
    }
    // The tail numbers are uniform: mean 1/2 within standard errors over pixels and samples.
    HaltonSampler<double> s(8, 8, 3, HaltonRandomization::digit_permutation, 4);
    Stats tail;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            for (std::uint64_t i = 0; i < 16; ++i) {
                s.start_pixel_sample(x, y, i);
                s.get_1d();
                for (int k = 0; k < 10; ++k) tail.add(s.get_1d());
            }
    INFO("tail mean " << tail.mean << " stderr " << tail.stderr_mean());
    CHECK(std::abs(tail.mean - 0.5) <= 4 * tail.stderr_mean());
}

// ---------------------------------------------------------------------------------------------
// Warps
// ---------------------------------------------------------------------------------------------

TEST_CASE("statistics: warps integrate known functions with their densities") {
    Pcg32 rng(5);
    const int n = 200000;
    auto u2 = [&] {
        const double a = rng.uniform<double>();
        return Vec2<double>(a, rng.uniform<double>());
    };
    SUBCASE("cosine hemisphere: int z^2 dw = 2pi/3, int 1 dw = 2pi") {
        check_unbiased([&] {
            const Vec3<double> d = square_to_cosine_hemisphere(u2());
            return d.z * d.z / cosine_hemisphere_pdf(d.z);
        }, 2 * pi<double> / 3, n);
        check_unbiased([&] {
            const Vec3<double> d = square_to_cosine_hemisphere(u2());
            return (d.x > 0 ? 1.0 : 0.0) / cosine_hemisphere_pdf(d.z);
        }, pi<double>, n);
    }
    SUBCASE("uniform sphere: int x^2 dw = 4pi/3, int [z>0.5] dw = pi") {
        check_unbiased([&] {
            const Vec3<double> d = square_to_uniform_sphere(u2());
            CHECK(std::abs(glm::length(d) - 1) < 1e-12);
            return d.x * d.x / uniform_sphere_pdf<double>();
        }, 4 * pi<double> / 3, n);
        check_unbiased([&] {
            const Vec3<double> d = square_to_uniform_sphere(u2());
            return (d.z > 0.5 ? 1.0 : 0.0) / uniform_sphere_pdf<double>();
        }, pi<double>, n);
    }
    SUBCASE("uniform hemisphere: int z dw = pi, int x^2 dw = 2pi/3") {
        check_unbiased([&] {
            const Vec3<double> d = square_to_uniform_hemisphere(u2());
            CHECK(d.z > 0);
            return d.z / uniform_hemisphere_pdf<double>();
        }, pi<double>, n);
        check_unbiased([&] {
            const Vec3<double> d = square_to_uniform_hemisphere(u2());
            return d.x * d.x / uniform_hemisphere_pdf<double>();
        }, 2 * pi<double> / 3, n);
    }
    SUBCASE("triangle: int x^2 dA over (0,0),(2,0),(0,1) = 2/3") {
        const Vec3<double> a(0, 0, 0), b(2, 0, 0), c(0, 1, 0);
        const double area = triangle_area(a, b, c);
        CHECK(area == doctest::Approx(1.0));
        check_unbiased([&] {
            const Vec3<double> p = sample_triangle(a, b, c, u2());
            return p.x * p.x * area;
        }, 2.0 / 3.0, n);
    }
    SUBCASE("polygon: a unit square split into fan triangles is sampled uniformly") {
        const Vec3<double> v[] = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0.5, 1.5, 1}, {0, 1, 1}};
        PolygonSampler<double> poly(v);
        CHECK(poly.area() == doctest::Approx(1.25));
        CHECK(poly.normal().z == doctest::Approx(1.0));
        // int x dA: square 1/2 + top triangle (area 1/4, centroid x 1/2) 1/8 = 5/8.
        check_unbiased([&] {
            const Vec3<double> p = poly.sample(u2());
            return p.x * poly.area();
        }, 5.0 / 8.0, n);
        // int [y > 1] dA = 1/4.
        check_unbiased([&] { return (poly.sample(u2()).y > 1 ? 1.0 : 0.0) * poly.area(); }, 0.25, n);
        const std::vector<Vec3<double>> collinear = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
        CHECK_THROWS_AS(PolygonSampler<double>{collinear}, Error);
        CHECK_THROWS_AS(PolygonSampler<double>{std::span<const Vec3<double>>(v, 2)}, Error);
    }
}

TEST_CASE("stress: warps at the corners of the unit square give finite unit vectors") {
    for (double x : {0.0, 1.0, std::nextafter(1.0, 0.0), 0.5}) {
        for (double y : {0.0, 1.0, std::nextafter(1.0, 0.0), 0.5}) {
            const Vec2<double> u(x, y);
            for (const Vec3<double>& d :
                 {square_to_cosine_hemisphere(u), square_to_uniform_sphere(u),
                  square_to_uniform_hemisphere(u)}) {
                CHECK(all_finite(d));
                CHECK(std::abs(glm::length(d) - 1) < 1e-12);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Russian roulette and BRDF selection (Szécsi 2009, §2)
// ---------------------------------------------------------------------------------------------

namespace {

using Rgbd = Rgb<double>;

/// One reflection with L_in(w) = (1 + z) * tint off glint's material (tracer/brdf.hpp) seen
/// from the normal, where its Phong lobe (n + 2)/(2 pi) cos^e(theta) cos(theta) is about the
/// normal and covers the hemisphere: the exact reflected radiance is
/// kd (1 + 2/3) tint + ks (1 + (e+2)/(e+3)) tint.
/// W divides the whole w by the selected lobe's density: with the glossy lobe selected,
/// w_d / p_g ~ cos^(1-e), whose variance is infinite for e >= 3 (Szécsi 2009, §2.1: "the specular
/// sampling cannot sample the whole domain of the diffuse reflection"), so a finite-sample mean
/// cannot be tested against standard errors. W is therefore tested with e = 2, DIS and MIS
/// with a sharp e = 20.
template <BrdfSelection C>
void check_scatter_unbiased(const Roulette<double, 3>& roulette, std::uint64_t seed, int depth = 0) {
    const double exponent = C == BrdfSelection::weighted ? 2.0 : 20.0;
    const auto material = Material<double>::glossy(Rgbd(0.5, 0.3, 0.1), Rgbd(0.2, 0.4, 0.6), exponent);
    const SurfaceBrdf<double> brdf(material, Vec3<double>(0, 0, 1));
    const Rgbd tint(1.0, 0.5, 2.0);
    const Rgbd throughput(0.2, 1.0, 0.6);  // what the walk carried so far
    const double e = exponent;
    const Rgbd exact = (material.kd * (1 + 2.0 / 3.0) + material.ks * (1 + (e + 2) / (e + 3))) * tint;
    Pcg32 rng(seed);
    std::array<Stats, 3> stats;
    const int n = 1'000'000;
    for (int k = 0; k < n; ++k) {
        const double us = rng.uniform<double>();
        const Vec2<double> ud(rng.uniform<double>(), rng.uniform<double>());
        const ScatterSample<double, 3> s = scatter(brdf, roulette, throughput, us, ud, depth, C);
        Rgbd value = s.offset;
        if (!s.terminated()) value += s.weight * tint * (1 + s.direction.z);
        for (int l = 0; l < 3; ++l) stats[l].add(value[l]);
    }
    for (int l = 0; l < 3; ++l) {
        INFO(std::string(short_name(C)) << " band " << l << ": mean " << stats[l].mean << " exact " << exact[l]
                           << " stderr " << stats[l].stderr_mean());
        CHECK(std::abs(stats[l].mean - exact[l]) < 4 * stats[l].stderr_mean());
    }
}

template <BrdfSelection C>
void check_all_roulettes(std::uint64_t seed) {
    using R = Roulette<double, 3>;
    SUBCASE("classic") { check_scatter_unbiased<C>(R::classic(), seed); }
    SUBCASE("classic mean") { check_scatter_unbiased<C>(R::mean(), seed + 1); }
    SUBCASE("spectral") { check_scatter_unbiased<C>(R::spectral(), seed + 2); }
    SUBCASE("radiance estimate") {
        R r = R::spectral();
        r.estimate = Rgbd(0.8, 0.5, 1.5);
        check_scatter_unbiased<C>(r, seed + 3);
    }
    SUBCASE("radiance estimate, classic inside") {
        R r = R::classic();
        r.estimate = Rgbd(0.8, 0.5, 1.5);
        check_scatter_unbiased<C>(r, seed + 4);
    }
    SUBCASE("radiance estimate, reduced continuation") {
        R r = R::classic();
        r.estimate = Rgbd(0.8, 0.5, 1.5);
        r.goodness = 0.4;
        check_scatter_unbiased<C>(r, seed + 10);
    }
    // The throughput rule before its first decision (no termination) and after it, with the
    // max norm, Szécsi 2009, §2.2's H-weighted norm, and a radiance estimate on top; no roulette.
    R t = R::throughput(ThroughputNorm::max, 2);
    SUBCASE("throughput, before min_depth") { check_scatter_unbiased<C>(t, seed + 5, 1); }
    SUBCASE("throughput, after min_depth") { check_scatter_unbiased<C>(t, seed + 6, 2); }
    SUBCASE("throughput, H-weighted norm") {
        t.norm = ThroughputNorm::weighted;
        check_scatter_unbiased<C>(t, seed + 7, 5);
    }
    SUBCASE("throughput + radiance estimate") {
        t.estimate = Rgbd(0.8, 0.5, 1.5);
        check_scatter_unbiased<C>(t, seed + 8, 3);
    }
    SUBCASE("no roulette") { check_scatter_unbiased<C>(R::none(), seed + 9, 7); }
}

}  // namespace

static_assert(RoulettePolicy<Roulette<float, 3>, float, 3>);
static_assert(RoulettePolicy<Roulette<double, 8>, double, 8>);

TEST_CASE("exact: a roulette's identity values give zero offsets and leave s unchanged") {
    using R = Roulette<double, 3>;
    const Rgbd F(0.3, 0.9, 0.5), a(0.6, 0.2, 0.7);
    for (R r : {R::classic(), R::spectral(), R::throughput(ThroughputNorm::weighted, 0, 0.95), R::none(0.01)}) {
        CHECK(r.terminated(a) == Rgbd(0.0));
        CHECK(r.continued_offset(a, 0.3) == Rgbd(0.0));
        const double s = r.continuation(F, a, 4);
        r.goodness = 0.5;  // s d / (1 - (1 - d) s)
        CHECK(r.continuation(F, a, 4) == doctest::Approx(s * 0.5 / (1 - 0.5 * s)));
        r.estimate = Rgbd(2.0);
        CHECK(r.terminated(a) == a * 2.0);
        CHECK(r.continued_offset(a, 0.25) == a * 2.0 * -3.0);
    }
}

TEST_CASE("statistics: DIS with every roulette is unbiased (10^6 samples)") {
    check_all_roulettes<BrdfSelection::decomposition>(100);
}
TEST_CASE("statistics: W with every roulette is unbiased (10^6 samples)") {
    check_all_roulettes<BrdfSelection::weighted>(200);
}
TEST_CASE("statistics: MIS with every roulette is unbiased (10^6 samples)") {
    check_all_roulettes<BrdfSelection::mis>(300);
}

TEST_CASE("exact: spectral roulette stops blue light on a yellow surface, equals classic on grey") {
    const auto spectral = Roulette<double, 3>::spectral();
    const auto classic = Roulette<double, 3>::classic();
    const Rgbd yellow(1, 1, 0), blue(0, 0, 1);
    // Szécsi 2009, §2.2: classic continues with the mean albedo (2/3 for uniform weights).
    CHECK(spectral.selection_weight(blue, yellow) == 0.0);
    CHECK(Roulette<double, 3>::mean().selection_weight(blue, yellow) == doctest::Approx(2.0 / 3.0));
    const std::array<Rgbd, 1> lobes = {yellow};
    for (double u : {0.0, 0.3, 0.999}) {
        CHECK(select_lobe(spectral, blue, std::span<const Rgbd>(lobes), u, 0).terminated());
    }
    // A yellow diffuse + blue specular surface lit by blue selects the specular lobe always.
    const std::array<Rgbd, 2> two = {Rgbd(0.8, 0.8, 0), Rgbd(0, 0, 0.9)};
    const auto sel = select_lobe(spectral, blue, std::span<const Rgbd>(two), 0.5, 0);
    CHECK(sel.probability[0] == 0.0);
    CHECK(sel.probability[1] == doctest::Approx(0.9));
    CHECK(sel.lobe == 1);
    // Grey albedo, any throughput: spectral == classic (luminance weights sum to 1).
    Pcg32 rng(3);
    for (int k = 0; k < 1000; ++k) {
        const double g = rng.uniform<double>();
        const Rgbd F(rng.uniform<double>(), rng.uniform<double>(), rng.uniform<double>());
        CHECK(spectral.selection_weight(F, Rgbd(g)) == doctest::Approx(classic.selection_weight(F, Rgbd(g))).epsilon(1e-12));
    }
    // White throughput: spectral == classic for any albedo.
    CHECK(spectral.selection_weight(Rgbd(1), Rgbd(0.9, 0.2, 0.4)) ==
          doctest::Approx(classic.selection_weight(Rgbd(1), Rgbd(0.9, 0.2, 0.4))));
}

TEST_CASE("exact: global radiance estimate and its configuration errors") {
    // Closed furnace of area S with diffuse emitters of radiance e: Phi_e = pi S e, so
    // L~ = a e / (1 - a): the reflected part of the exact e / (1 - a), an underestimate.
    const double S = 6.0, e = 0.3, a = 0.7;
    const Rgbd L = global_radiance_estimate(Rgbd(pi<double> * S * e), S, Rgbd(a));
    CHECK(L[0] == doctest::Approx(a * e / (1 - a)));
    CHECK(L[0] < e / (1 - a));
    CHECK_THROWS_AS(global_radiance_estimate(Rgbd(1), 0.0, Rgbd(0.5)), Error);
    CHECK_THROWS_AS(global_radiance_estimate(Rgbd(1), 1.0, Rgbd(1.0)), Error);
    CHECK_THROWS_AS(global_radiance_estimate(Rgbd(-1), 1.0, Rgbd(0.5)), Error);
}

TEST_CASE("exact: pilot fit, goodness and its floor; no roulette never terminates") {
    // Two vertices of albedo 1/2, two samples each: X = (1, 3) and (2, 2) in every band.
    const Rgbd a(0.5), H(1.0 / 3.0);
    const std::array<RoulettePilotSample<double, 3>, 4> s = {{{a, Rgbd(1.0)}, {a, Rgbd(3.0)}, {a, Rgbd(2.0)}, {a, Rgbd(2.0)}}};
    const std::span<const RoulettePilotSample<double, 3>> v(s);
    // Least squares: L~ = sum x a / sum a^2 = 8 * 0.5 / (4 * 0.25) = 4, so a L~ = mean x = 2.
    const Rgbd L = fitted_radiance_estimate(v);
    CHECK(L[0] == doctest::Approx(4.0));
    // d = sum (x - 2)^2 / sum x^2 = 2 / 18; the floor = mean within-vertex variance (2 and 0,
    // n - 1 = 1) over mean x^2 (5 and 4): 1 / 4.5.
    CHECK(estimate_goodness(v, L, H) == doctest::Approx(2.0 / 18.0));
    CHECK(estimate_goodness_floor(v, 2, H) == doctest::Approx(1.0 / 4.5));
    CHECK_THROWS_AS(estimate_goodness_floor(v, 1, H), Error);
    // No roulette: some lobe is always chosen, however dark the albedo; with a cut-off, walks
    // whose throughput falls to it stop.
    const std::array<Rgbd, 2> lobes = {Rgbd(0.01), Rgbd(0.0)};
    const auto cut = Roulette<double, 3>::none(0.02);
    for (double u : {0.0, 0.5, 0.999999}) {
        const auto sel = select_lobe(Roulette<double, 3>::none(), Rgbd(1.0), std::span<const Rgbd>(lobes), u, 100);
        CHECK(sel.lobe == 0);
        CHECK(sel.total == 1.0);
        CHECK(select_lobe(cut, Rgbd(1.0), std::span<const Rgbd>(lobes), u, 0).terminated());
        CHECK(select_lobe(cut, Rgbd(3.0), std::span<const Rgbd>(lobes), u, 0).lobe == 0);
    }
}

namespace {

/// The furnace of Szécsi 2009, §2.2 as a toy walk: every surface has albedo a
/// and emission 1 - a per band, so the radiance is 1 everywhere. Returns the per-walk
/// estimates of the H-weighted radiance; `steps` counts the reflections.
MomentStats furnace_walks(const Roulette<double, 3>& roulette, const Rgbd& albedo, int walks, std::uint64_t seed,
                          double& steps) {
    Pcg32 rng(seed);
    MomentStats out;
    const std::array<Rgbd, 1> lobes = {albedo};
    const Rgbd emission = Rgbd(1.0) - albedo;
    steps = 0;
    for (int k = 0; k < walks; ++k) {
        Rgbd F(1.0), result(0.0);
        for (int depth = 0; depth < 1000; ++depth) {
            result += F * emission;
            const auto sel = select_lobe(roulette, F, std::span<const Rgbd>(lobes), rng.uniform<double>(), depth);
            result += F * sel.offset;
            if (sel.terminated()) break;
            steps += 1;
            F *= albedo / sel.probability[0];  // W = w/p = a for ideal sampling
        }
        out.add(result.luminance());
    }
    steps /= walks;
    return out;
}

}  // namespace

TEST_CASE("statistics: furnace walks are unbiased, spectral and radiance estimate cut variance") {
    // Saturated walls: a permutation of (1.0, 0.5, 0.2) in Szécsi 2009, §2.2; 1.0 would never terminate, so
    // (0.9, 0.5, 0.2). The exact luminance of the radiance is 1.
    const Rgbd albedo(0.9, 0.5, 0.2);
    const int walks = 200000;
    double steps_classic = 0, steps_spectral = 0, steps_estimate = 0;
    const MomentStats classic = furnace_walks(Roulette<double, 3>::classic(), albedo, walks, 1, steps_classic);
    const MomentStats spectral = furnace_walks(Roulette<double, 3>::spectral(), albedo, walks, 2, steps_spectral);
    // L~ from the scene: area S, Phi_e = pi S (1 - a), mean albedo a (one material).
    auto with_estimate = Roulette<double, 3>::spectral();
    with_estimate.estimate = global_radiance_estimate(Rgbd(pi<double>) * (Rgbd(1.0) - albedo), 1.0, albedo);
    const MomentStats estimate = furnace_walks(with_estimate, albedo, walks, 3, steps_estimate);
    for (const MomentStats* s : {&classic, &spectral, &estimate}) {
        INFO("mean " << s->mean() << " variance " << s->variance());
        CHECK(std::abs(s->mean() - 1.0) < 4 * std::sqrt(s->variance() / walks));
    }
    // The radiance estimate lowers the variance of the spectral roulette's walk at the same
    // continuation probabilities (same mean walk length). (The classic walk's throughput grows
    // as (0.9/0.59)^k in red: its variance is heavy-tailed and is only reported.)
    const double diff_se = std::hypot(spectral.variance_stderr(), estimate.variance_stderr());
    INFO("variance classic " << classic.variance() << " spectral " << spectral.variance()
                             << " spectral with estimate " << estimate.variance()
                             << " (se of difference " << diff_se << ")");
    CHECK(estimate.variance() + 4 * diff_se < spectral.variance());
    CHECK(steps_estimate == doctest::Approx(steps_spectral).epsilon(0.02));
}

// ---------------------------------------------------------------------------------------------
// Multiple correlated sampling (Szécsi 2009, §3)
// ---------------------------------------------------------------------------------------------

namespace {

/// Textbook form factor from a differential area to a parallel rectangle a x b at distance h,
/// the area's normal through one corner of the rectangle (Howell's catalogue, case B-3).
double corner_form_factor(double a, double b, double h) {
    const double A = a / h, B = b / h;
    const double sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
    return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2 * pi<double>);
}

/// Monte Carlo estimate of the integral of G (clamped cosines) over a polygon.
Stats geometry_integral_mc(const Vec3<double>& x, const Vec3<double>& n,
                           std::span<const Vec3<double>> v, int samples, std::uint64_t seed) {
    PolygonSampler<double> poly(v);
    Pcg32 rng(seed);
    Stats s;
    for (int k = 0; k < samples; ++k) {
        const Vec3<double> y = poly.sample(Vec2<double>(rng.uniform<double>(), rng.uniform<double>()));
        const Vec3<double> d = y - x;
        const double r2 = glm::dot(d, d);
        const double cx = std::max(0.0, glm::dot(d, n)), cy = std::abs(glm::dot(d, poly.normal()));
        s.add(cx * cy / (r2 * r2) * poly.area());
    }
    return s;
}

}  // namespace

TEST_CASE("exact: eq. 3.4 form factor of a unit square from points on its axis") {
    for (double h : {0.05, 0.3, 1.0, 2.5, 10.0}) {
        // Square [-1/2, 1/2]^2 at height h, facing down; receiver at the origin facing up.
        const Vec3<double> sq[] = {{-0.5, -0.5, h}, {-0.5, 0.5, h}, {0.5, 0.5, h}, {0.5, -0.5, h}};
        const double exact = 4 * corner_form_factor(0.5, 0.5, h);
        const Vec3<double> x(0, 0, 0), n(0, 0, 1);
        INFO("h = " << h);
        CHECK(point_to_polygon_form_factor<double>(x, n, sq) == doctest::Approx(exact).epsilon(1e-12));
        // Winding does not matter.
        const Vec3<double> rev[] = {sq[3], sq[2], sq[1], sq[0]};
        CHECK(point_to_polygon_form_factor<double>(x, n, rev) == doctest::Approx(exact).epsilon(1e-12));
        // Corner case of the catalogue directly: receiver under a corner of a 1 x 1 square.
        const Vec3<double> c[] = {{0, 0, h}, {1, 0, h}, {1, 1, h}, {0, 1, h}};
        CHECK(point_to_polygon_form_factor<double>(x, n, c) ==
              doctest::Approx(corner_form_factor(1, 1, h)).epsilon(1e-12));
        CHECK(point_to_polygon_form_factor<float>(Vec3<float>(0), Vec3<float>(0, 0, 1),
                                                  std::vector<Vec3<float>>{{-0.5f, -0.5f, float(h)}, {-0.5f, 0.5f, float(h)},
                                                   {0.5f, 0.5f, float(h)}, {0.5f, -0.5f, float(h)}}) ==
              doctest::Approx(exact).epsilon(1e-5));
    }
    // A huge square close by covers the hemisphere: form factor -> 1.
    const Vec3<double> big[] = {{-1e4, -1e4, 1}, {1e4, -1e4, 1}, {1e4, 1e4, 1}, {-1e4, 1e4, 1}};
    CHECK(point_to_polygon_form_factor<double>(Vec3<double>(0), Vec3<double>(0, 0, 1), big) ==
          doctest::Approx(1.0).epsilon(1e-4));
}

TEST_CASE("agreement: eq. 3.4 against Monte Carlo on tilted and horizon-straddling polygons") {
    Pcg32 rng(77);
    for (int t = 0; t < 12; ++t) {
        const Vec3<double> x(0, 0, 0);
        const Vec3<double> n = safe_normalize(Vec3<double>(rng.uniform<double>() - 0.5, rng.uniform<double>() - 0.5, 1.0));
        // Random triangle around (0, 0, 1); some straddle the tangent plane of x.
        std::vector<Vec3<double>> tri;
        for (int k = 0; k < 3; ++k)
            tri.emplace_back(4 * rng.uniform<double>() - 2, 4 * rng.uniform<double>() - 2,
                             1.5 * rng.uniform<double>() - 0.3);
        const double formula = polygon_geometry_integral<double>(x, n, tri);
        const Stats mc = geometry_integral_mc(x, n, tri, 200000, 1000 + t);
        INFO("triangle " << t << ": formula " << formula << " mc " << mc.mean << " se " << mc.stderr_mean());
        CHECK(std::abs(formula - mc.mean) < 4 * mc.stderr_mean() + 1e-12);
    }
}

namespace {

struct DirectScene {
    // Large light (side 2) close above the receiver, whose point x lies under one edge, so G
    // varies strongly over the light.
    std::vector<Vec3<double>> verts = {{-1, -1, 0.5}, {-1, 1, 0.5}, {1, 1, 0.5}, {1, -1, 0.5}};
    PolygonLight<double, 3> light{verts, Rgbd(4.0, 2.0, 1.0)};
    Vec3<double> x{-1, 0, 0}, n{0, 0, 1};
    Rgbd albedo{0.7, 0.5, 0.3};
    Rgbd fr() const { return albedo / pi<double>; }
};

}  // namespace

TEST_CASE("PolygonLight: either winding with LightSides::both; the front side decides with the default") {
    DirectScene s;
    const std::vector<Vec3<double>> reversed(s.verts.rbegin(), s.verts.rend());
    const PolygonLight<double, 3> front_ccw{s.verts, Rgbd(4.0, 2.0, 1.0)};
    const PolygonLight<double, 3> front_cw{reversed, Rgbd(4.0, 2.0, 1.0)};
    const PolygonLight<double, 3> both_cw{reversed, Rgbd(4.0, 2.0, 1.0), LightSides::both};
    const PolygonLight<double, 3> both_ccw{s.verts, Rgbd(4.0, 2.0, 1.0), LightSides::both};
    Pcg32 rng(21);
    std::array<Vec2<double>, 16> u;
    for (auto& v : u) v = Vec2<double>(rng.uniform<double>(), rng.uniform<double>());
    auto direct = [&](const PolygonLight<double, 3>& light) {
        return correlated_direct(light, s.x, s.n, [&](const Vec3<double>&) { return s.fr(); }, s.fr(),
                                 [](const Vec3<double>&, const Vec3<double>&) { return true; },
                                 std::span<const Vec2<double>>(u));
    };
    // The receiver is below the light; the vertex order of DirectScene faces it.
    const auto ref = direct(front_ccw), cw = direct(both_cw), ccw = direct(both_ccw), back = direct(front_cw);
    REQUIRE(ref.combined[0] > 0.0);
    for (int l = 0; l < 3; ++l) {
        CHECK(cw.combined[l] == doctest::Approx(ref.combined[l]).epsilon(1e-12));
        CHECK(cw.main_part[l] == doctest::Approx(ref.main_part[l]).epsilon(1e-12));
        CHECK(ccw.combined[l] == doctest::Approx(ref.combined[l]).epsilon(1e-12));
        CHECK(back.combined[l] == 0.0);  // a front-only light seen from behind: documented, by choice
    }
}

TEST_CASE("exact: correlated direct lighting has zero variance for a fully visible diffuse light") {
    DirectScene s;
    const Rgbd J = s.light.radiance() * s.fr() * s.light.geometry_integral(s.x, s.n);
    Pcg32 rng(8);
    // The order of the two draws is fixed (second coordinate first, the order GCC evaluated the
    // constructor's arguments in when the thresholds below were set): argument evaluation order
    // is unspecified, and clang's order gave another sample set.
    auto draw = [&] {
        const double second = rng.uniform<double>();
        return Vec2<double>(rng.uniform<double>(), second);
    };
    std::array<Vec2<double>, 16> u;
    Stats is_stats;
    for (int trial = 0; trial < 2000; ++trial) {
        for (auto& v : u) v = draw();
        const auto r = correlated_direct(s.light, s.x, s.n, [&](const Vec3<double>&) { return s.fr(); },
                                         s.fr(), [](const Vec3<double>&, const Vec3<double>&) { return true; },
                                         std::span<const Vec2<double>>(u));
        for (int l = 0; l < 3; ++l) {
            REQUIRE(r.lambda[l] == 1.0);
            REQUIRE(std::abs(r.combined[l] - J[l]) <= 1e-13 * J[l]);
            REQUIRE(std::abs(r.correlated[l] - J[l]) <= 1e-13 * J[l]);
        }
        is_stats.add(r.importance[0]);
    }
    // ... while importance sampling alone is noisy but unbiased around the same value.
    CHECK(is_stats.variance() > 1e-4 * J[0] * J[0]);
    CHECK(std::abs(is_stats.mean - J[0]) < 4 * is_stats.stderr_mean());
    // The literal eq. 3.3 (denominator centred on J) gives lambda slightly below 1.
    for (auto& v : u) v = draw();
    const auto lit = correlated_direct(s.light, s.x, s.n, [&](const Vec3<double>&) { return s.fr(); },
                                       s.fr(), [](const Vec3<double>&, const Vec3<double>&) { return true; },
                                       std::span<const Vec2<double>>(u), LambdaEstimate::eq33);
    CHECK(lit.lambda[0] < 1.0);
    CHECK(lit.lambda[0] > 0.5);
}

TEST_CASE("exact: correlated direct lighting of a fully occluded light is the importance answer, 0") {
    DirectScene s;
    Pcg32 rng(9);
    std::array<Vec2<double>, 16> u;
    for (int trial = 0; trial < 200; ++trial) {
        for (auto& v : u) v = Vec2<double>(rng.uniform<double>(), rng.uniform<double>());
        for (auto form : {LambdaEstimate::regression, LambdaEstimate::eq33}) {
            const auto r = correlated_direct(s.light, s.x, s.n, [&](const Vec3<double>&) { return s.fr(); },
                                             s.fr(), [](const Vec3<double>&, const Vec3<double>&) { return false; },
                                             std::span<const Vec2<double>>(u), form);
            for (int l = 0; l < 3; ++l) {
                REQUIRE(r.lambda[l] == 0.0);
                REQUIRE(r.combined[l] == 0.0);
                REQUIRE(r.importance[l] == 0.0);
                REQUIRE(r.correlated[l] != 0.0);  // correlated sampling alone is wrong here
            }
        }
    }
}

TEST_CASE("statistics: half-occluded light: the combination beats importance and correlated sampling") {
    // Receiver under the centre of a large, close light (G strongly peaked); the half y.x > 0 is
    // hidden. By symmetry importance sampling (lambda 0) and correlated sampling (lambda 1) have
    // the same variance and the optimum is lambda = 1/2. Exact: eq. 3.4 on the visible half.
    DirectScene s;
    s.x = Vec3<double>(0, 0, 0.25);
    const std::vector<Vec3<double>> visible_half = {{-1, -1, 0.5}, {-1, 1, 0.5}, {0, 1, 0.5}, {0, -1, 0.5}};
    const double exact = (s.light.radiance() * s.fr())[0] * polygon_geometry_integral<double>(s.x, s.n, visible_half);
    const int trials = 20000;
    Pcg32 rng(10);
    std::array<Vec2<double>, 32> u;
    Stats err_combined, err_importance, err_correlated, diff_is, diff_cs, importance;
    for (int trial = 0; trial < trials; ++trial) {
        for (auto& v : u) v = Vec2<double>(rng.uniform<double>(), rng.uniform<double>());
        const auto r = correlated_direct(s.light, s.x, s.n, [&](const Vec3<double>&) { return s.fr(); },
                                         s.fr(), [](const Vec3<double>&, const Vec3<double>& y) { return y.x < 0; },
                                         std::span<const Vec2<double>>(u));
        const double ec = std::pow(r.combined[0] - exact, 2), ei = std::pow(r.importance[0] - exact, 2),
                     es = std::pow(r.correlated[0] - exact, 2);
        err_combined.add(ec);
        err_importance.add(ei);
        err_correlated.add(es);
        diff_is.add(ec - ei);
        diff_cs.add(ec - es);
        importance.add(r.importance[0]);
    }
    INFO("MSE combined " << err_combined.mean << " importance " << err_importance.mean
                         << " correlated " << err_correlated.mean);
    // Paired comparison of squared errors (bias of the estimated lambda included): the
    // combination's is smaller by more than 4 standard errors of the difference.
    CHECK(diff_is.mean + 4 * diff_is.stderr_mean() < 0);
    CHECK(diff_cs.mean + 4 * diff_cs.stderr_mean() < 0);
    // The reference value is right: importance sampling is unbiased around it.
    CHECK(std::abs(importance.mean - exact) < 4 * importance.stderr_mean());
}

TEST_CASE("exact: filter_lambda pools neighbouring pixels' co-moments") {
    // Pixel k has samples (f, g) = (c_k g, g) for g in {1, 2, 3}: lambda_k = c_k alone.
    const int w = 3, h = 2;
    std::vector<CorrelatedStats<double>> stats(w * h);
    std::vector<double> J(w * h, 2.0), lambda(w * h), pooled(w * h);
    for (int k = 0; k < w * h; ++k)
        for (double g : {1.0, 2.0, 3.0}) stats[std::size_t(k)].add(0.5 * (k + 1) * g, g);
    filter_lambda<double>(stats, J, w, h, 0, lambda);
    for (int k = 0; k < w * h; ++k) CHECK(lambda[std::size_t(k)] == doctest::Approx(0.5 * (k + 1)));
    // Radius 1 on a 3x2 image: every g-variance is equal, so pooled lambda is the window mean.
    filter_lambda<double>(stats, J, w, h, 1, pooled);
    CHECK(pooled[0] == doctest::Approx((0.5 + 1.0 + 2.0 + 2.5) / 4));  // pixels 0,1,3,4
    CHECK(pooled[1] == doctest::Approx((0.5 + 1.0 + 1.5 + 2.0 + 2.5 + 3.0) / 6));
    CHECK_THROWS_AS(filter_lambda<double>(stats, J, w, h + 1, 1, pooled), Error);
}

TEST_CASE("exact: equal-solid-angle sphere cells and the closed-form diffuse a_d") {
    for (bool hemi : {true, false}) {
        SphereCells<double> cells(6, 4, hemi);
        double omega = 0, cosine = 0;
        for (std::size_t d = 0; d < cells.count(); ++d) {
            omega += cells.solid_angle();
            cosine += cells.cosine_integral(d);
            CHECK(cells.cosine_integral(d) >= 0.0);
        }
        CHECK(omega == doctest::Approx(hemi ? 2 * pi<double> : 4 * pi<double>));
        CHECK(cosine == doctest::Approx(pi<double>));  // integral of max(cos, 0) over the sphere
        // Monte Carlo of cos over one cell agrees with the closed form.
        Pcg32 rng(hemi ? 1 : 2);
        for (std::size_t d : {std::size_t(0), std::size_t(7), std::size_t(13)}) {
            check_unbiased([&] {
                const Vec3<double> wv = cells.sample(d, Vec2<double>(rng.uniform<double>(), rng.uniform<double>()));
                return std::max(wv.z, 0.0) * cells.solid_angle();
            }, cells.cosine_integral(d), 100000);
        }
    }
    CHECK_THROWS_AS(SphereCells<double>(0, 3), Error);
}

TEST_CASE("exact: sphere cells' direction integral, least cosine and cell lookup (Szécsi 2009, §3.3.1)") {
    const SphereCells<double> cells(8, 4, false);
    Vec3<double> total(0.0);
    Pcg32 rng(41);
    for (std::size_t d = 0; d < cells.count(); ++d) {
        total += cells.direction_integral(d);
        // Upper cells: V_d . z is section 3.3.1's closed-form cosine integral.
        if (cells.cos_boundary(int(d / 8) + 1) >= 0.0)
            CHECK(cells.direction_integral(d).z == doctest::Approx(cells.cosine_integral(d)).epsilon(1e-12));
        for (int t = 0; t < 20; ++t) {
            const Vec2<double> u(0.02 + 0.96 * rng.uniform<double>(), 0.02 + 0.96 * rng.uniform<double>());
            REQUIRE(cells.cell_of(cells.sample(d, u)) == d);
        }
    }
    CHECK(glm::length(total) < 1e-12);  // the whole sphere's integral of w is 0
    for (int t = 0; t < 20; ++t) {
        const Vec3<double> n = glm::normalize(Vec3<double>(rng.uniform<double>() - 0.5, rng.uniform<double>() - 0.5,
                                                           rng.uniform<double>() - 0.5));
        for (std::size_t d = 0; d < cells.count(); ++d) {
            // The least n . w over a 100 x 100 grid of the cell (edges included): never below the
            // exact least value, and within the grid's spacing of it.
            double least = 2;
            for (int a = 0; a <= 100; ++a)
                for (int b = 0; b <= 100; ++b)
                    least = std::min(least, glm::dot(n, cells.sample(d, Vec2<double>(a / 100.0, b / 100.0))));
            const double exact = cells.min_cosine(d, n);
            REQUIRE(exact <= least + 1e-12);
            REQUIRE(exact >= least - 2e-3);
        }
    }
    // n . V_d against Monte Carlo over a cell the tangent plane of n cuts: the signed integral.
    const Vec3<double> n = glm::normalize(Vec3<double>(0.3, -0.4, 0.2));
    check_unbiased([&] {
        return glm::dot(n, cells.sample(5, Vec2<double>(rng.uniform<double>(), rng.uniform<double>()))) * cells.solid_angle();
    }, glm::dot(n, cells.direction_integral(5)), 100000);
}

TEST_CASE("statistics: the leave-one-out combined estimate is unbiased where eq. 3.3's lambda is not") {
    // g/p = 1 + u, f/p = g/p where u < 0.3 (visible), else 0: with 4 samples, lambda from the
    // same samples correlates with them. The leave-one-out estimate is unbiased within 4
    // standard errors; with f = g it is J exactly.
    const double J = 1.5, exact = 0.3 + 0.045;
    Pcg32 rng(43);
    std::array<double, 4> f, g;
    Stats loo, same;
    for (int t = 0; t < 400000; ++t) {
        CorrelatedStats<double> st;
        for (std::size_t i = 0; i < 4; ++i) {
            const double u = rng.uniform<double>();
            g[i] = 1.0 + u;
            f[i] = u < 0.3 ? g[i] : 0.0;
            st.add(f[i], g[i]);
        }
        loo.add(leave_one_out_estimate<double>(f, g, J));
        same.add(st.estimate(J, std::clamp(st.lambda(J), 0.0, 1.0)));
    }
    INFO("leave-one-out " << loo.mean << " +- " << loo.stderr_mean() << ", same-sample lambda " << same.mean
                          << " +- " << same.stderr_mean() << ", exact " << exact);
    CHECK(std::abs(loo.mean - exact) < 4 * loo.stderr_mean());
    CHECK(std::abs(same.mean - exact) > 4 * same.stderr_mean());
    const std::array<double, 4> g2{1.0, 1.2, 1.7, 1.9};
    CHECK(leave_one_out_estimate<double>(g2, g2, J) == doctest::Approx(J).epsilon(1e-12));
}

namespace {

struct EnvScene {
    SphereCells<double> cells{6, 4};
    std::vector<Rgbd> averages, albedo;
    Rgbd rho{0.8, 0.6, 0.4};
    template <class Env>
    explicit EnvScene(Env&& env) {
        averages.resize(cells.count());
        albedo.resize(cells.count());
        environment_cell_averages<double, 3>(cells, env, averages);
        for (std::size_t d = 0; d < cells.count(); ++d) albedo[d] = rho / pi<double> * cells.cosine_integral(d);
    }
    Rgbd fr() const { return rho / pi<double>; }
};

}  // namespace

TEST_CASE("exact: correlated environment lighting is exact for a cell-wise constant, visible sky") {
    // Radiance constant in each cell: main part eq. 3.6 equals the integrand.
    SphereCells<double> grid{6, 4};
    auto env = [&](const Vec3<double>& w) {
        const int j = std::min(3, int((1 - w.z) * 4));
        const double phi = std::atan2(w.y, w.x) + (w.y < 0 ? 2 * pi<double> : 0.0);
        const int i = std::min(5, int(phi / (2 * pi<double>) * 6));
        return Rgbd(1.0 + j + 0.5 * i, 2.0, 0.5 + 0.1 * i);
    };
    EnvScene s(env);
    Rgbd exact(0.0);
    for (std::size_t d = 0; d < s.cells.count(); ++d) exact += s.averages[d] * s.albedo[d];
    Pcg32 rng(21);
    std::vector<Vec2<double>> u(s.cells.count() * 8);
    for (int trial = 0; trial < 200; ++trial) {
        // Keep samples inside the cells' interiors so the cell lookup of env() is unambiguous.
        for (auto& v : u) v = Vec2<double>(0.01 + 0.98 * rng.uniform<double>(), 0.01 + 0.98 * rng.uniform<double>());
        const auto r = correlated_environment<double, 3>(
            s.cells, s.averages, s.albedo, env, [&](const Vec3<double>&) { return s.fr(); },
            [](const Vec3<double>&) { return true; }, u, 8, EnvironmentMainPart::brdf);
        for (int l = 0; l < 3; ++l) REQUIRE(std::abs(r.combined[l] - exact[l]) <= 1e-12 * exact[l]);
    }
}

TEST_CASE("statistics: correlated environment lighting with both main parts, half occluded") {
    // Smooth sky L = 1 + z, diffuse receiver, half the hemisphere (x < 0) occluded:
    // exact = rho/pi (int_{x>0} z + z^2 dw) = rho/pi (pi/2 + pi/3) = 5 rho / 6.
    auto env = [](const Vec3<double>& w) { return Rgbd(1.0 + w.z); };
    EnvScene s(env);
    const double exact = 5.0 * s.rho[0] / 6.0;
    for (auto part : {EnvironmentMainPart::radiance, EnvironmentMainPart::brdf}) {
        Pcg32 rng(part == EnvironmentMainPart::radiance ? 31 : 32);
        std::vector<Vec2<double>> u(s.cells.count() * 16);
        Stats comb, imp, corr;
        for (int trial = 0; trial < 4000; ++trial) {
            for (auto& v : u) v = Vec2<double>(rng.uniform<double>(), rng.uniform<double>());
            const auto r = correlated_environment<double, 3>(
                s.cells, s.averages, s.albedo, env, [&](const Vec3<double>&) { return s.fr(); },
                [](const Vec3<double>& w) { return w.x > 0; }, u, 16, part);
            comb.add(r.combined[0]);
            imp.add(r.importance[0]);
            corr.add(r.correlated[0]);
        }
        INFO("main part " << (part == EnvironmentMainPart::radiance ? "3.5" : "3.6") << ": combined "
                          << comb.mean << " +- " << comb.stderr_mean() << ", importance " << imp.mean
                          << " +- " << imp.stderr_mean() << ", exact " << exact);
        CHECK(std::abs(imp.mean - exact) < 4 * imp.stderr_mean());
        CHECK(std::abs(corr.mean - exact) < 4 * corr.stderr_mean());
        CHECK(std::abs(comb.mean - exact) < 4 * comb.stderr_mean());
        CHECK(comb.variance() < imp.variance());
    }
}

TEST_CASE("stress: float instantiations, degenerate and non-finite inputs give no NaN") {
    // float versions compile and agree with double.
    const SurfaceBrdf<float> brdf(Material<float>::glossy(Rgb<float>(0.5f, 0.3f, 0.1f), Rgb<float>(0.2f, 0.4f, 0.6f), 20.0f),
                                  Vec3<float>(0, 0, 1));
    const auto s = scatter(brdf, Roulette<float, 3>::spectral(), Rgb<float>(1.0f), 0.1f, Vec2<float>(0.3f, 0.7f), 0);
    CHECK_FALSE(s.terminated());
    CHECK(s.weight.is_finite());
    const std::vector<Vec3<float>> sq = {{-0.5f, -0.5f, 1}, {-0.5f, 0.5f, 1}, {0.5f, 0.5f, 1}, {0.5f, -0.5f, 1}};
    PolygonLight<float, 3> light(sq, Rgb<float>(1.0f));
    const std::array<Vec2<float>, 4> u = {Vec2<float>(0.1f, 0.2f), Vec2<float>(0.5f, 0.5f),
                                          Vec2<float>(0.9f, 0.3f), Vec2<float>(0.4f, 0.8f)};
    const auto r = correlated_direct(light, Vec3<float>(0), Vec3<float>(0, 0, 1),
                                     [](const Vec3<float>&) { return Rgb<float>(0.2f); }, Rgb<float>(0.2f),
                                     [](const Vec3<float>&, const Vec3<float>&) { return true; },
                                     std::span<const Vec2<float>>(u));
    CHECK(r.combined[0] == doctest::Approx(r.main_part[0]).epsilon(1e-5));
    // A NaN or infinite throughput terminates the walk without producing NaN.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const std::array<Rgbd, 1> lobe = {Rgbd(0.5)};
    for (const Rgbd& F : {Rgbd(nan), Rgbd(std::numeric_limits<double>::infinity()), Rgbd(0.0)}) {
        for (int depth : {0, 5})
            CHECK(select_lobe(Roulette<double, 3>::throughput(), F, std::span<const Rgbd>(lobe), 0.2, depth).terminated());
        const auto sel = select_lobe(Roulette<double, 3>::spectral(), F, std::span<const Rgbd>(lobe), 0.2, 0);
        CHECK(sel.terminated());
        CHECK(sel.offset.is_finite());
    }
    // Receiver in the light's plane, behind it, or a polygon seen edge-on: J = 0, no NaN.
    const std::vector<Vec3<double>> sqd = {{-0.5, -0.5, 1}, {-0.5, 0.5, 1}, {0.5, 0.5, 1}, {0.5, -0.5, 1}};
    PolygonLight<double, 3> dl(sqd, Rgbd(1.0));
    CHECK(dl.geometry_integral(Vec3<double>(2, 0, 1), Vec3<double>(0, 0, 1)) == 0.0);
    CHECK(dl.geometry_integral(Vec3<double>(0, 0, 2), Vec3<double>(0, 0, -1)) == 0.0);
    CHECK(polygon_geometry_integral<double>(Vec3<double>(0, 0, 1), Vec3<double>(1, 0, 0), sqd) == 0.0);
    CHECK(std::isfinite(polygon_geometry_integral<double>(Vec3<double>(0.5, 0.5, 1), Vec3<double>(0, 0, -1), sqd)));
}
