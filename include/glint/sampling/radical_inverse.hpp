// glint/sampling/radical_inverse.hpp: exact integer radical inverse, its inverse, and the
// digit scramblings (random digit permutation, Owen's nested scrambling) Halton builds on.
//
// Larsen 2004, §6.1: Phi_b(i) = sum_j a_j(i) b^(-j-1) where i = sum_j a_j(i) b^j,
// "the number obtained by expressing i in base b, reversing the digits and placing the point
// at the beginning" (eq. 6.1; the extraction split the exponents "b^(-j-1)" and "b^j" across
// lines, repaired here). Check values from Larsen 2004, §6.1: Phi_10(1234) = 0.4321,
// Phi_10(524) = 0.425, Phi_10(2) = 0.2, Phi_10(23) = 0.32; base 2 prefix (eq. 6.2)
// 0, 1/2, 1/4, 3/4, 1/8, 3/8, ... (the extraction lost the fraction bars).
//
// Exactness: the digits are reversed in integers (reversed digits r and b^k in 128 bits), then
// floor(r / b^k * 2^64) is computed by exact integer division. That 64-bit fixed-point
// fraction is truncated to float/double, so the result is the largest T <= Phi_b(i): exact
// whenever Phi_b(i) is representable, never rounded up, and therefore strictly below 1.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include <glint/core/math.hpp>
#include <glint/core/random.hpp>

namespace glint {

namespace detail {

__extension__ typedef unsigned __int128 u128;

/// floor(num * 2^64 / den) for num < den (den < 2^127). One 128-bit division when den <= 2^64,
/// else exact restoring long division.
constexpr std::uint64_t floor_fraction(u128 num, u128 den) {
    if (den <= (u128(1) << 64)) return static_cast<std::uint64_t>((num << 64) / den);
    std::uint64_t q = 0;
    for (int bit = 0; bit < 64; ++bit) {
        num <<= 1;
        q <<= 1;
        if (num >= den) {
            num -= den;
            q |= 1u;
        }
    }
    return q;
}

/// Bit reversal of a 64-bit word (the base-2 radical inverse as a 64-bit fraction).
constexpr std::uint64_t reverse_bits_64(std::uint64_t v) {
    v = ((v >> 1) & 0x5555555555555555ULL) | ((v & 0x5555555555555555ULL) << 1);
    v = ((v >> 2) & 0x3333333333333333ULL) | ((v & 0x3333333333333333ULL) << 2);
    v = ((v >> 4) & 0x0F0F0F0F0F0F0F0FULL) | ((v & 0x0F0F0F0F0F0F0F0FULL) << 4);
    v = ((v >> 8) & 0x00FF00FF00FF00FFULL) | ((v & 0x00FF00FF00FF00FFULL) << 8);
    v = ((v >> 16) & 0x0000FFFF0000FFFFULL) | ((v & 0x0000FFFF0000FFFFULL) << 16);
    return (v >> 32) | (v << 32);
}

/// Element i of a pseudo-random permutation of {0, ..., n-1} chosen by `key` (Kensler,
/// "Correlated Multi-Jittered Sampling", 2013: a hash that is a bijection on the next power of
/// two, cycle-walked down to n). n <= 2^31.
constexpr std::uint32_t permutation_element(std::uint32_t i, std::uint32_t n, std::uint32_t key) {
    std::uint32_t w = n - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    do {
        i ^= key;
        i *= 0xe170893du;
        i ^= key >> 16;
        i ^= (i & w) >> 4;
        i ^= key >> 8;
        i *= 0x0929eb3fu;
        i ^= key >> 23;
        i ^= (i & w) >> 1;
        i *= 1u | key >> 27;
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5;
    } while (i >= n);
    return (i + key) % n;
}

}  // namespace detail

/// Exact floor(n / d) for every 64-bit n by one multiply-high, a subtraction, an addition and
/// two shifts, with no division (Granlund and Montgomery, "Division by invariant integers using
/// multiplication", PLDI 1994, Figure 4.1): with l = ceil(log2 d) and
/// m = floor(2^64 (2^l - d) / d) + 1 < 2^64, t = floor(m n / 2^64) and
/// floor(n / d) = (t + (n - t) / 2) / 2^(l-1) (shifts; for l = 0 both shifts are 0).
/// The digit loops of the permuted radical inverse divide by a base this way.
class InvariantDivisor {
public:
    constexpr InvariantDivisor() = default;
    /// d >= 1 (the caller checks; glint divides by prime bases and their powers).
    constexpr explicit InvariantDivisor(std::uint32_t d) : divisor_(d) {
        int l = 0;
        while ((std::uint64_t(1) << l) < d) ++l;
        const detail::u128 numerator = (detail::u128(1) << 64) * ((detail::u128(1) << l) - d);
        multiplier_ = static_cast<std::uint64_t>(numerator / d + 1);
        reciprocal32_ = d > 1 ? ~std::uint64_t(0) / d + 1 : 0;
        shift1_ = l < 1 ? l : 1;
        shift2_ = l > 0 ? l - 1 : 0;
    }
    /// The divisor d given at construction (1 by default).
    constexpr std::uint32_t divisor() const { return divisor_; }
    /// floor(n / d), exact for every 64-bit n.
    constexpr std::uint64_t quotient(std::uint64_t n) const {
        const auto t = static_cast<std::uint64_t>((detail::u128(multiplier_) * n) >> 64);
        return (t + ((n - t) >> shift1_)) >> shift2_;
    }
    /// floor(n / d) for 32-bit n by one multiply-high alone: with c = floor((2^64 - 1) / d) + 1,
    /// floor(c n / 2^64) = floor(n / d) for all n, d < 2^32 (Lemire, Kaser, Kurz, "Faster
    /// remainder by direct computation", 2019, Theorem 1 with N = 32, F = 64).
    constexpr std::uint32_t quotient32(std::uint32_t n) const {
        return static_cast<std::uint32_t>((detail::u128(reciprocal32_) * n) >> 64);
    }

private:
    std::uint64_t reciprocal32_ = 0;  // c of quotient32 (0 for d = 1, where 2^64 / d overflows)
    std::uint64_t multiplier_ = 1;
    std::uint32_t divisor_ = 1;
    int shift1_ = 0, shift2_ = 0;
};

/// Largest T not above the 64-bit fixed-point fraction `bits` * 2^-64 (truncation, so < 1).
template <Scalar T>
constexpr T fraction_to_unit(std::uint64_t bits) {
    constexpr int p = std::numeric_limits<T>::digits;  // 24 or 53
    return static_cast<T>(bits >> (64 - p)) * (T(1) / static_cast<T>(std::uint64_t(1) << p));
}

/// floor(Phi_base(index) * 2^64): the exact radical inverse as a 64-bit fraction.
/// Precondition: 2 <= base < 2^32 (glint uses the primes table).
constexpr std::uint64_t radical_inverse_bits(std::uint32_t base, std::uint64_t index) {
    if (base == 2) return detail::reverse_bits_64(index);
    detail::u128 reversed = 0, denominator = 1;
    while (index != 0) {
        const std::uint64_t next = index / base;
        const std::uint64_t digit = index - next * base;
        reversed = reversed * base + digit;
        denominator *= base;
        index = next;
    }
    return detail::floor_fraction(reversed, denominator);
}

/// Phi_base(index) rounded down to T: exact for representable values, always < 1.
template <Scalar T>
constexpr T radical_inverse(std::uint32_t base, std::uint64_t index) {
    return fraction_to_unit<T>(radical_inverse_bits(base, index));
}

/// The index whose first `digits` base-`base` digits, reversed, are the digits of `inverse`:
/// inverse_radical_inverse(Phi_b(i) * b^digits, b, digits) == i mod b^digits. Used by the
/// per-pixel Halton sampler (pbrt-v4's InverseRadicalInverse).
constexpr std::uint64_t inverse_radical_inverse(std::uint64_t inverse, std::uint32_t base,
                                                int digits) {
    std::uint64_t index = 0;
    for (int i = 0; i < digits; ++i) {
        const std::uint64_t next = inverse / base;
        index = index * base + (inverse - next * base);
        inverse = next;
    }
    return index;
}

/// Number of base-b digits a scrambled radical inverse uses: the largest n with b^n < 2^64.
constexpr int scrambled_digit_count(std::uint32_t base) {
    int n = 0;
    std::uint64_t power = 1;
    while (power <= std::numeric_limits<std::uint64_t>::max() / base) {
        power *= base;
        ++n;
    }
    return n;
}

/// Radical inverse with every digit position j mapped through its own permutation
/// perm[j * base + digit] (random digit permutation; Faure / Tezuka style). All `digits` =
/// scrambled_digit_count(base) positions are permuted (leading zeros included, since a
/// permutation need not fix 0), so indices must be below base^digits. Once the index has no
/// digits left the rest is the constant tail[j] = sum_{t >= j} perm_t(0) base^(digits-1-t),
/// precomputed by permuted_digit_tails (tail has digits + 1 entries, tail[digits] = 0).
constexpr std::uint64_t permuted_radical_inverse_bits(std::uint32_t base, std::uint64_t index,
                                                      const std::uint16_t* perm,
                                                      const std::uint64_t* tail, int digits) {
    detail::u128 reversed = 0, denominator = 1;
    int j = 0;
    for (; j < digits && index != 0; ++j) {
        const std::uint64_t next = index / base;
        const auto digit = static_cast<std::uint32_t>(index - next * base);
        reversed = reversed * base + perm[std::size_t(j) * base + digit];
        denominator *= base;
        index = next;
    }
    // Shift the j reversed digits up by the remaining digits - j places and add the tail.
    detail::u128 full_denominator = denominator;
    for (int t = j; t < digits; ++t) {
        reversed *= base;
        full_denominator *= base;
    }
    return detail::floor_fraction(reversed + tail[j], full_denominator);
}

/// tail[j] for permuted_radical_inverse_bits: the value of digit positions j .. digits-1 when
/// all of them are zero, i.e. sum_{t >= j} perm_t(0) base^(digits-1-t).
constexpr void permuted_digit_tails(std::uint32_t base, const std::uint16_t* perm, int digits,
                                    std::uint64_t* tail) {
    tail[digits] = 0;
    std::uint64_t place = 1;  // base^(digits-1-t)
    for (int t = digits - 1; t >= 0; --t) {
        tail[t] = tail[t + 1] + perm[std::size_t(t) * base] * place;
        if (t > 0) place *= base;
    }
}

/// Owen's nested uniform scrambling: output digit j is permuted by a random permutation
/// chosen by hashing (seed, j, the j preceding digits), i.e. index mod base^j. Every node of the
/// base-b digit tree gets its own permutation, which keeps the net structure and makes each
/// point uniform on [0,1). All `digits` positions are scrambled: a digit 0 beyond the index's
/// own digits lies in a node shared with larger indices, so it cannot be replaced by an
/// independent random digit without breaking the stratification.
constexpr std::uint64_t owen_scrambled_radical_inverse_bits(std::uint32_t base,
                                                            std::uint64_t index,
                                                            std::uint64_t seed, int digits) {
    // base^digits < 2^64, so everything fits in 64 bits until the final division.
    std::uint64_t reversed = 0, denominator = 1;  // denominator = base^j, also the place of digit j
    std::uint64_t prefix = 0;                      // index mod base^j
    for (int j = 0; j < digits; ++j) {
        const std::uint64_t next = index / base;
        const auto digit = static_cast<std::uint32_t>(index - next * base);
        const std::uint64_t key =
            detail::mix_bits(seed ^ detail::mix_bits(prefix + (std::uint64_t(j) << 56)));
        reversed = reversed * base +
                   detail::permutation_element(digit, base, static_cast<std::uint32_t>(key));
        prefix += digit * denominator;
        denominator *= base;
        index = next;
    }
    return detail::floor_fraction(reversed, denominator);
}

}  // namespace glint
