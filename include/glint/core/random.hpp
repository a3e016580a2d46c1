// glint/core/random.hpp: PCG32, the small seedable generator all of glint's randomness uses.
//
// O'Neill, "PCG: A Family of Simple Fast Space-Efficient Statistically Good Algorithms for
// Random Number Generation" (2014): 64-bit LCG state, XSH-RR output permutation.
#pragma once

#include <cstdint>

namespace glint {
namespace detail {

/// SplitMix64's finalizer (Steele, Lea, Flood 2014): a bijective 64-bit mixer, for hashing
/// seeds and scramble keys.
constexpr std::uint64_t mix_bits(std::uint64_t v) {
    v ^= v >> 31;
    v *= 0x7fb5d329728ea185ULL;
    v ^= v >> 27;
    v *= 0x81dadef4bc2dd44dULL;
    v ^= v >> 33;
    return v;
}

}  // namespace detail

/// PCG32 generator (O'Neill 2014): 64-bit state, 32-bit outputs, period 2^64 per stream.
/// Cheap to copy; one per thread or per path. Satisfies std::uniform_random_bit_generator.
class Pcg32 {
public:
    /// Type of one raw output.
    using result_type = std::uint32_t;

    /// `seed` picks the starting point, `stream` one of 2^63 independent sequences.
    explicit constexpr Pcg32(std::uint64_t seed = 0x853c49e6748fea9bULL,
                             std::uint64_t stream = 0xda3e39cb94b95bdbULL) {
        seed_with(seed, stream);
    }

    /// Restarts the generator as Pcg32(seed, stream) would. Related seeds give dependent
    /// sequences; use hashed() for seeds derived from indices.
    constexpr void seed_with(std::uint64_t seed, std::uint64_t stream) {
        state_ = 0u;
        inc_ = (stream << 1u) | 1u;
        next_u32();
        state_ += seed;
        next_u32();
    }

    /// A generator for the key (seed, stream) with both hashed first. PCG32 started from related
    /// seeds (consecutive integers: states a fixed offset apart) or related streams (increments
    /// a fixed offset apart) gives dependent sequences; every seed derived from pixel, sample
    /// or path indices goes through here.
    static constexpr Pcg32 hashed(std::uint64_t seed, std::uint64_t stream) {
        const std::uint64_t s = detail::mix_bits(stream ^ 0x6a09e667f3bcc909ULL);
        return Pcg32(detail::mix_bits(seed ^ s), detail::mix_bits(s + 0x9e3779b97f4a7c15ULL));
    }

    /// Next raw output, uniform over all 2^32 values; advances the state by one step.
    constexpr std::uint32_t next_u32() {
        const std::uint64_t old = state_;
        state_ = old * 6364136223846793005ULL + inc_;
        const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
        const auto rot = static_cast<std::uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
    }

    /// 64 uniform bits from two next_u32() calls (first call in the high half).
    constexpr std::uint64_t next_u64() {
        const std::uint64_t hi = next_u32();
        return (hi << 32) | next_u32();
    }

    /// Uniform in [0, 1), never 1: 24 random bits for float, 53 for double.
    template <class T = float>
    constexpr T uniform() {
        if constexpr (sizeof(T) == 4) {
            return static_cast<T>(next_u32() >> 8) * T(0x1p-24);
        } else {
            return static_cast<T>(next_u64() >> 11) * T(0x1p-53);
        }
    }

    /// Uniform integer in [0, bound) without modulo bias (Lemire's method).
    constexpr std::uint32_t bounded(std::uint32_t bound) {
        std::uint64_t m = std::uint64_t(next_u32()) * bound;
        auto low = static_cast<std::uint32_t>(m);
        if (low < bound) {
            const std::uint32_t threshold = (0u - bound) % bound;
            while (low < threshold) {
                m = std::uint64_t(next_u32()) * bound;
                low = static_cast<std::uint32_t>(m);
            }
        }
        return static_cast<std::uint32_t>(m >> 32);
    }

    // UniformRandomBitGenerator interface, so <random> distributions accept it.
    /// Smallest output, 0.
    static constexpr result_type min() { return 0; }
    /// Largest output, 2^32 - 1.
    static constexpr result_type max() { return 0xffffffffu; }
    /// next_u32(), so that `<random>` distributions and std::shuffle accept a Pcg32.
    constexpr result_type operator()() { return next_u32(); }

private:
    std::uint64_t state_ = 0;
    std::uint64_t inc_ = 1;
};

}  // namespace glint
