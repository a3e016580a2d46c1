// glint/sampling/permuted_radical_inverse.hpp: radical inverses with random digit permutations,
// computed from precomputed tables at the precision of T; the fast randomized Halton dimensions
// HaltonSampler draws in the path tracer.
//
// Random digit permutation (pbrt-v4, Pharr, Jakob, Humphreys, 4th ed., 2023, 8.6.2 "Random
// digit permutations"): digit j of the base-b expansion of the index is mapped through its own
// random permutation pi_j of {0, ..., b-1} before it is placed at b^(-j-1) (Larsen 2004, §6.1,
// eq. 6.1, is the case pi_j = identity). Every position is permuted, the index's leading zeros
// included, so each output digit is uniform on {0, ..., b-1} and independent of the others; the
// n digits kept give a value uniform on the grid k / b^n. A per-dimension random offset
// u in [0, 1) of the last kept digit then makes each point exactly uniform on [0, 1) (over the
// seed), so estimators stay unbiased; within one seed the first b^k points of a dimension still
// fall one into each interval [i / b^k, (i+1) / b^k) (k <= n): the permutations reorder strata
// but never merge them.
//
// Speed (what makes this cheaper than halton.hpp's exact 64-bit Halton<T>):
// - n is the smallest digit count with b^n >= 2^digits(T) (24 digits of base 2 for float), not
//   every digit a 64-bit fraction can hold;
// - digits are taken k at a time: a "digit group" of base B = b^k (B <= max_group_base) is one
//   table entry holding the k permuted, reversed digits, so base 5 in float takes 3 table
//   lookups instead of 11 digit steps;
// - the quotient by B is a multiply-high by a precomputed reciprocal (InvariantDivisor,
//   radical_inverse.hpp), never a division instruction;
// - the result is (R + u) / B^M in double arithmetic with 1 / B^M precomputed (R the integer of
//   the permuted reversed digits): no 128-bit arithmetic.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/sampling/primes.hpp>
#include <glint/sampling/radical_inverse.hpp>

namespace glint {

/// Digit grouping of one base: `digits` = group_digits * groups base-b digits are kept, taken
/// group_digits at a time (group base b^group_digits <= max(max_group_base, b)).
struct DigitGrouping {
    int group_digits = 1;  ///< Base-b digits looked up together in one table entry (>= 1).
    int groups = 1;        ///< Number of such lookups per radical inverse (>= 1).
};

/// The grouping for base b at `precision` bits: `preferred_groups` groups of the fewest digits
/// that reach 2^precision, if b^digits < 2^64 and the group base stays <= max(max_group_base, b)
/// (a fixed group count lets the lookups be unrolled, with no loop branch to mispredict);
/// otherwise the fewest groups that keep min(ceil(precision / log2 b), scrambled_digit_count(b))
/// digits.
constexpr DigitGrouping digit_grouping(std::uint32_t b, int precision, std::uint32_t max_group_base,
                                       int preferred_groups) {
    const int max_digits = scrambled_digit_count(b);  // b^max_digits < 2^64
    const detail::u128 target = detail::u128(1) << precision;
    std::uint64_t group_base = b;
    for (int k = 1; k * preferred_groups <= max_digits && group_base <= std::max(max_group_base, b);
         ++k, group_base *= b) {
        detail::u128 power = 1;
        for (int i = 0; i < preferred_groups; ++i) power *= group_base;
        if (power >= target) return {k, preferred_groups};
    }
    int need = 0;
    for (detail::u128 power = 1; power < target && need < max_digits; ++need) power *= b;
    int k_max = 1;
    for (std::uint64_t power = std::uint64_t(b) * b; power <= max_group_base; power *= b) ++k_max;
    const int groups = (need + k_max - 1) / k_max;
    const int k = (need + groups - 1) / groups;
    if (k * groups > max_digits) return {1, need};
    return {k, groups};
}

/// Radical inverses of dimensions 0 .. dims-1 (base primes[dim]), each digit position of each
/// dimension >= identity_dims permuted by its own random permutation drawn from seed; dimensions
/// below identity_dims are the plain radical inverse truncated to the kept digits. Construction
/// allocates (about groups * b^group_digits 16-bit entries per dimension); operator() neither
/// allocates nor throws. Copies share nothing and cost the tables: share one by reference.
template <Scalar T>
class PermutedRadicalInverse {
public:
    /// Tables for dimensions 0 .. dims-1 (dims in [1, prime_count]) drawn from `seed`; the first
    /// identity_dims dimensions stay unpermuted; a lookup table holds at most
    /// max(max_group_base, b) entries (max_group_base in [2, 65536]). Throws Error otherwise.
    PermutedRadicalInverse(std::size_t dims, std::uint64_t seed, std::size_t identity_dims = 0,
                           std::uint32_t max_group_base = 4096) {
        if (dims == 0 || dims > prime_count)
            throw Error("glint::PermutedRadicalInverse: dimension count " + std::to_string(dims) +
                        " outside [1, " + std::to_string(prime_count) + "] (one prime base each)");
        if (max_group_base < 2 || max_group_base > 65536)
            throw Error("glint::PermutedRadicalInverse: max_group_base " + std::to_string(max_group_base) +
                        " outside [2, 65536] (table entries are 16-bit)");
        Pcg32 rng(seed, 0x7065726d75746564ULL);  // "permuted"
        dims_.resize(dims);
        for (std::size_t d = 0; d < dims; ++d) build_dimension(d, d < identity_dims, max_group_base, rng);
    }

    /// Number of dimensions with tables.
    std::size_t dims() const { return dims_.size(); }
    /// The prime base of dimension `dim`, primes[dim] (2, 3, 5, ...).
    std::uint32_t base(std::size_t dim) const { return primes[dim]; }
    /// Number of base-b digits kept for dimension `dim` (b^digits >= 2^digits(T) unless
    /// b^digits would reach 2^64).
    int digits(std::size_t dim) const { return dims_[dim].k * dims_[dim].groups; }
    /// pi_position(digit) of dimension `dim` (position < digits(dim), digit < base(dim)).
    std::uint16_t permutation(std::size_t dim, int position, std::uint32_t digit) const {
        return perms_[dims_[dim].perm_offset + std::size_t(position) * primes[dim] + digit];
    }
    /// The random offset u in [0, 1) of the last kept digit (0 for identity dimensions).
    double offset(std::size_t dim) const { return dims_[dim].offset; }

    /// R = sum_{j < digits} pi_j(a_j) b^(digits-1-j), a_j the base-b digits of `index`: the
    /// permuted, reversed digits as an integer (< b^digits). Digits above the kept ones are
    /// ignored (the value depends on index mod b^digits).
    std::uint64_t reversed_digits(std::size_t dim, std::uint64_t index) const {
        const Dimension& d = dims_[dim];
        const std::uint16_t* table = tables_.data() + d.table_offset;
        const std::uint64_t B = d.divisor.divisor();
        std::uint64_t reversed = 0;
        for (int g = 0; g < d.groups; ++g, table += B) {
            const std::uint64_t next = d.divisor.quotient(index);
            reversed = reversed * B + table[index - next * B];
            index = next;
        }
        return reversed;
    }

    /// Coordinate `dim` (< dims()) of point `index`: (R + u) / b^digits, in [0, 1).
    T operator()(std::size_t dim, std::uint64_t index) const {
        const Dimension& d = dims_[dim];
        const std::uint64_t r = d.groups == fixed_groups ? reversed_fixed(d, index) : reversed_digits(dim, index);
        const double x = (double(r) + d.offset) * d.scale;
        return std::min(static_cast<T>(x), T(1) - std::numeric_limits<T>::epsilon() / T(2));
    }

    /// The group count of (almost) every dimension: 4 groups of >= 6 bits for float, 6 of
    /// >= 9 bits for double.
    static constexpr int fixed_groups = std::numeric_limits<T>::digits <= 24 ? 4 : 6;

private:
    struct Dimension {
        InvariantDivisor divisor;     // by the group base B = b^k
        int k = 1, groups = 1;        // digits per group, groups
        double scale = 1, offset = 0; // 1 / b^(k groups), u
        std::size_t table_offset = 0; // groups tables of B entries in tables_
        std::size_t perm_offset = 0;  // k groups permutations of b entries in perms_
    };

    /// reversed_digits for the fixed group count, unrolled; 32-bit indices (every index of a
    /// render below 2^32 points) by the one-multiply quotient.
    std::uint64_t reversed_fixed(const Dimension& d, std::uint64_t index) const {
        const std::uint16_t* table = tables_.data() + d.table_offset;
        const std::uint32_t B = d.divisor.divisor();
        std::uint64_t reversed = 0;
        if (index <= 0xffffffffu && B > 1) {
            auto i = static_cast<std::uint32_t>(index);
            for (int g = 0; g < fixed_groups; ++g, table += B) {  // constant trip count: unrolled
                const std::uint32_t next = d.divisor.quotient32(i);
                reversed = reversed * B + table[i - next * B];
                i = next;
            }
            return reversed;
        }
        for (int g = 0; g < fixed_groups; ++g, table += B) {
            const std::uint64_t next = d.divisor.quotient(index);
            reversed = reversed * B + table[index - next * B];
            index = next;
        }
        return reversed;
    }

    void build_dimension(std::size_t dim, bool identity, std::uint32_t max_group_base, Pcg32& rng) {
        const std::uint32_t b = primes[dim];
        const DigitGrouping grouping =
            digit_grouping(b, std::numeric_limits<T>::digits, max_group_base, fixed_groups);
        Dimension& d = dims_[dim];
        d.k = grouping.group_digits;
        d.groups = grouping.groups;
        std::uint32_t B = 1;
        for (int i = 0; i < d.k; ++i) B *= b;
        d.divisor = InvariantDivisor(B);
        long double power = 1;
        for (int i = 0; i < d.k * d.groups; ++i) power *= b;
        d.scale = double(1.0L / power);
        d.offset = identity ? 0.0 : rng.uniform<double>();
        // One permutation of {0..b-1} per kept digit position (Fisher-Yates), identity if asked.
        d.perm_offset = perms_.size();
        const int digits = d.k * d.groups;
        perms_.resize(perms_.size() + std::size_t(digits) * b);
        for (int j = 0; j < digits; ++j) {
            std::uint16_t* p = perms_.data() + d.perm_offset + std::size_t(j) * b;
            for (std::uint32_t i = 0; i < b; ++i) p[i] = static_cast<std::uint16_t>(i);
            if (identity) continue;
            for (std::uint32_t i = b - 1; i > 0; --i) std::swap(p[i], p[rng.bounded(i + 1)]);
        }
        // Group table g, entry v (the k digits a_t of v, lowest first, are digit positions
        // g k + t): sum_t pi_{gk+t}(a_t) b^(k-1-t).
        d.table_offset = tables_.size();
        tables_.resize(tables_.size() + std::size_t(d.groups) * B);
        for (int g = 0; g < d.groups; ++g) {
            for (std::uint32_t v = 0; v < B; ++v) {
                std::uint32_t rest = v, value = 0;
                for (int t = 0; t < d.k; ++t, rest /= b)
                    value = value * b + perms_[d.perm_offset + std::size_t(g * d.k + t) * b + rest % b];
                tables_[d.table_offset + std::size_t(g) * B + v] = static_cast<std::uint16_t>(value);
            }
        }
    }

    std::vector<Dimension> dims_;
    std::vector<std::uint16_t> perms_;   // [dim][digit position][digit]
    std::vector<std::uint16_t> tables_;  // [dim][group][group value]
};

}  // namespace glint
