// glint/trees/sah_binning.hpp: the object binning of the binned SAH builder (bvh_builder.hpp).
//
// Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies" (IEEE RT 2007), §3:
// a node's references are put in bins by their box centres on all three axes in one pass,
// each bin growing its box and its count, and the node's references are then partitioned at
// the chosen boundary. Here a reference's box is read as two 4-float vectors (SSE2, every
// x86-64 CPU; plain loops elsewhere, the same floats), a bin's box grows by one minimum of 8
// floats (SahBins: AVX2 where the CPU has it), the sweep skips empty bins, and the partition,
// without a branch per reference, returns the two sides' centre boxes, which are their
// children's binning ranges: no node reads its references only to find their centres.
// SpatialBins: the equal-width bins of the spatial split search (Stich et al. 2009, §3).
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>

#include <glint/core/aabb.hpp>
#include <glint/core/isa.hpp>
#include <glint/core/math.hpp>
#include <glint/trees/binary_bvh.hpp>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace glint {

namespace detail {

/// A reference: a primitive and the box of its part in the node that holds it (the whole
/// primitive's box unless spatial splits chopped it). `left`: its side in a spatial split.
struct BvhRef {
    AABB<float> box;
    std::uint32_t prim = 0;
    std::uint32_t left = 0;
};

/// The cheapest bin boundary found at a node: axis (-1: none), the first bin of the right
/// side, the normalized cost, the two sides' boxes and reference counts.
struct SahSplit {
    int axis = -1;
    std::uint32_t bin = 0;
    float cost = infinity<float>;
    AABB<float> left, right;
    std::uint32_t n_left = 0, n_right = 0;
};

/// Four floats, x, y, z and a lane nobody reads: a box corner or a centre. Minimum and
/// maximum as SSE's minps / maxps (the second operand where either is NaN).
struct Float4 {
#if defined(__SSE2__)
    __m128 v;
    static Float4 load(const float* p) { return {_mm_loadu_ps(p)}; }
    static Float4 splat(float s) { return {_mm_set1_ps(s)}; }
    friend Float4 operator+(Float4 a, Float4 b) { return {_mm_add_ps(a.v, b.v)}; }
    friend Float4 operator-(Float4 a, Float4 b) { return {_mm_sub_ps(a.v, b.v)}; }
    friend Float4 operator*(Float4 a, Float4 b) { return {_mm_mul_ps(a.v, b.v)}; }
    Float4 operator-() const { return {_mm_xor_ps(v, _mm_set1_ps(-0.0f))}; }
    friend Float4 min(Float4 a, Float4 b) { return {_mm_min_ps(a.v, b.v)}; }
    friend Float4 max(Float4 a, Float4 b) { return {_mm_max_ps(a.v, b.v)}; }
    void store(float* p) const { _mm_storeu_ps(p, v); }
    /// The fourth lane set to 0.
    Float4 xyz0() const { return {_mm_and_ps(v, _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)))}; }
    /// Each lane truncated to an integer (lanes in 0 ... 2^31).
    void truncate(std::int32_t* out) const { _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(v)); }
    /// Whether lane i truncated to an integer is below x (lanes in 0 ... 2^31).
    bool truncated_below(int i, std::int32_t x) const {
        const __m128i below = _mm_cmplt_epi32(_mm_cvttps_epi32(v), _mm_set1_epi32(x));
        return (_mm_movemask_ps(_mm_castsi128_ps(below)) >> i) & 1;
    }
    /// a where f, else b, without a branch.
    static Float4 select(bool f, Float4 a, Float4 b) {
        const __m128 m = _mm_castsi128_ps(_mm_set1_epi32(-std::int32_t(f)));
        return {_mm_or_ps(_mm_and_ps(m, a.v), _mm_andnot_ps(m, b.v))};
    }
#else
    float v[4];
    static Float4 load(const float* p) {
        Float4 r;
        std::memcpy(r.v, p, sizeof r.v);
        return r;
    }
    static Float4 splat(float s) { return {{s, s, s, s}}; }
    template <class F>
    static Float4 map(Float4 a, Float4 b, F f) { return {{f(a.v[0], b.v[0]), f(a.v[1], b.v[1]), f(a.v[2], b.v[2]), f(a.v[3], b.v[3])}}; }
    friend Float4 operator+(Float4 a, Float4 b) { return map(a, b, [](float x, float y) { return x + y; }); }
    friend Float4 operator-(Float4 a, Float4 b) { return map(a, b, [](float x, float y) { return x - y; }); }
    friend Float4 operator*(Float4 a, Float4 b) { return map(a, b, [](float x, float y) { return x * y; }); }
    Float4 operator-() const { return {{-v[0], -v[1], -v[2], -v[3]}}; }
    friend Float4 min(Float4 a, Float4 b) { return map(a, b, [](float x, float y) { return x < y ? x : y; }); }
    friend Float4 max(Float4 a, Float4 b) { return map(a, b, [](float x, float y) { return x > y ? x : y; }); }
    void store(float* p) const { std::memcpy(p, v, sizeof v); }
    Float4 xyz0() const { return {{v[0], v[1], v[2], 0.0f}}; }
    void truncate(std::int32_t* out) const {
        for (int i = 0; i < 4; ++i) out[i] = std::int32_t(v[i]);
    }
    bool truncated_below(int i, std::int32_t x) const { return std::int32_t(v[i]) < x; }
    static Float4 select(bool f, Float4 a, Float4 b) { return f ? a : b; }
#endif
    /// The box's low corner (the fourth lane: hi.x), its high corner (the fourth lane: 0, not
    /// the bits of `prim`, which would make a denormal float).
    static Float4 lo(const BvhRef& r) { return load(&r.box.lo.x); }
    static Float4 hi(const BvhRef& r) { return load(&r.box.hi.x).xyz0(); }
    /// x, y, z of p, 0 in the fourth lane.
    static Float4 load3(const Vec3f& p) { return Float4{{p.x, p.y, p.z, 0.0f}}; }
    Vec3f xyz() const {
        float f[4];
        store(f);
        return {f[0], f[1], f[2]};
    }
};

/// How a node's centres map to bins: bin = min(bins - 1, max(0, (c - lo) k)) per axis, the
/// centre c = (box.lo + box.hi) / 2, in the same float operations as a scalar loop would do.
struct BinMap {
    Float4 lo, k, last;  // the centre box's low corner, bins per unit, bins - 1
    BinMap(const AABB<float>& cbox, const Vec3f& scale, std::uint32_t bins)
        : lo(Float4::load3(cbox.lo)), k(Float4::load3(scale)), last(Float4::splat(float(bins - 1))) {}
    static Float4 centre(const BvhRef& r) { return (Float4::lo(r) + Float4::hi(r)) * Float4::splat(0.5f); }
    /// The bins of centre c on the three axes (lane 3 is not meaningful).
    void bins(Float4 c, std::int32_t* out) const { scaled(c).truncate(out); }
    /// Whether centre c's bin on `axis` is below `bin`.
    bool below(Float4 c, int axis, std::uint32_t bin) const { return scaled(c).truncated_below(axis, std::int32_t(bin)); }

private:
    Float4 scaled(Float4 c) const { return min(max((c - lo) * k, Float4::splat(0.0f)), last); }
};

/// The object bins of one node on three axes (Wald 2007, §3.1): per bin, the box of the
/// references whose centre falls in it and their count. A bin's box is 8 floats, the low
/// corner and the negated high corner (each with a lane nobody reads), so that growing it is
/// a minimum of all 8: one AVX2 instruction where the CPU has AVX2 (chosen at run time, as
/// core/isa.hpp's kernels are), two SSE2 ones elsewhere, the same floats either way.
class SahBins {
public:
    static constexpr int max_bins = 64;  ///< BvhBuildOptions::bins at most.

    /// Bins refs[b, e) with `map`, over `bins` bins per axis, with AVX2 if `avx2`. Large
    /// ranges fill two sets of bins, even and odd references, merged at the end: neighbouring
    /// references, which often share a bin, then do not wait for each other's update.
    SahBins(const BvhRef* refs, std::uint32_t b, std::uint32_t e, const BinMap& map, std::uint32_t bins, bool avx2)
        : bins_(bins) {
        const std::uint32_t sets = e - b >= 4 * bins ? 2 : 1;
        for (std::uint32_t set = 0; set < sets; ++set)
            for (int a = 0; a < 3; ++a)
                for (std::uint32_t j = 0; j < bins; ++j) {
                    std::fill(box_[set][a][j], box_[set][a][j] + 8, infinity<float>);
                    n_[set][a][j] = 0;
                }
#if GLINT_X86 && defined(__SSE2__)
        if (avx2)
            fill_avx2(refs, b, e, map, sets);
        else
#endif
            fill(refs, b, e, map, sets);
        if (sets == 1) return;
        for (int a = 0; a < 3; ++a)
            for (std::uint32_t j = 0; j < bins; ++j) {
                float* p = box_[0][a][j];
                const float* q = box_[1][a][j];
                (min(Float4::load(p), Float4::load(q))).store(p);
                (min(Float4::load(p + 4), Float4::load(q + 4))).store(p + 4);
                n_[0][a][j] += n_[1][a][j];
            }
    }
    /// The bins of axis a that hold references, in order, as boxes, counts and bin numbers
    /// (sweep_bins' input); returns how many.
    std::uint32_t axis(int a, AABB<float>* box, std::uint32_t* n, std::uint32_t* bin) const {
        std::uint32_t m = 0;
        for (std::uint32_t j = 0; j < bins_; ++j) {  // written always, kept where not empty
            const float* p = box_[0][a][j];
            box[m] = {{p[0], p[1], p[2]}, {-p[4], -p[5], -p[6]}};
            n[m] = n_[0][a][j];
            bin[m] = j;
            m += n_[0][a][j] != 0;
        }
        return m;
    }

private:
    void fill(const BvhRef* refs, std::uint32_t b, std::uint32_t e, const BinMap& map, std::uint32_t sets) {
        std::int32_t bin[4];
        for (std::uint32_t i = b; i < e; ++i) {
            const Float4 lo = Float4::lo(refs[i]), hi = Float4::hi(refs[i]), neg = -hi;
            map.bins((lo + hi) * Float4::splat(0.5f), bin);
            const std::uint32_t set = (i - b) & (sets - 1);
            for (int a = 0; a < 3; ++a) {
                float* p = box_[set][a][bin[a]];
                min(Float4::load(p), lo).store(p);
                min(Float4::load(p + 4), neg).store(p + 4);
                ++n_[set][a][bin[a]];
            }
        }
    }
#if GLINT_X86 && defined(__SSE2__)
    GLINT_TARGET_AVX2 void fill_avx2(const BvhRef* refs, std::uint32_t b, std::uint32_t e, const BinMap& map,
                                     std::uint32_t sets) {
        const __m256 negate_hi = _mm256_setr_ps(0.0f, 0.0f, 0.0f, 0.0f, -0.0f, -0.0f, -0.0f, -0.0f);
        std::int32_t bin[4];
        for (std::uint32_t i = b; i < e; ++i) {
            const Float4 lo = Float4::lo(refs[i]), hi = Float4::hi(refs[i]);
            map.bins((lo + hi) * Float4::splat(0.5f), bin);
            const __m256 box = _mm256_xor_ps(_mm256_set_m128(hi.v, lo.v), negate_hi);
            const std::uint32_t set = (i - b) & (sets - 1);
            for (int a = 0; a < 3; ++a) {
                float* p = box_[set][a][bin[a]];
                _mm256_store_ps(p, _mm256_min_ps(_mm256_load_ps(p), box));
                ++n_[set][a][bin[a]];
            }
        }
    }
#endif

    std::uint32_t bins_;
    alignas(32) float box_[2][3][max_bins][8];  // low corner, lane, negated high corner, lane
    std::uint32_t n_[2][3][max_bins];
};

/// The SAH's constants as the sweeps use them (BvhBuildOptions): C_T, C_I, and leaf blocks.
struct SahCosts {
    float traversal, intersection;
    std::uint32_t leaf_block;
    int shift;  // log2(leaf_block), -1 where it is no power of 2
    explicit SahCosts(const BvhBuildOptions& opt)
        : traversal(opt.traversal_cost), intersection(opt.intersection_cost), leaf_block(opt.leaf_block),
          shift(std::has_single_bit(opt.leaf_block) ? std::countr_zero(opt.leaf_block) : -1) {}
    /// Leaf blocks started by n references (BvhBuildOptions::blocks, a shift where it can be).
    std::uint32_t blocks(std::uint32_t n) const {
        return shift >= 0 ? (n + leaf_block - 1) >> shift : (n + leaf_block - 1) / leaf_block;
    }
};

/// Spatial bin boundary j (0 ... bins) of `box` on axis a, bins of equal width (Stich et al.
/// 2009 §3): 0 is the box's low plane, bins its high one; non-decreasing in j. The spatial
/// binning and the spatial partition use these same floats.
inline float spatial_plane(const AABB<float>& box, int a, std::uint32_t j, std::uint32_t bins) {
    if (j >= bins) return box.hi[a];
    return std::min(box.hi[a], box.lo[a] + (box.hi[a] - box.lo[a]) * (float(j) / float(bins)));
}

/// The spatial bins of one axis of a node box: their planes (spatial_plane for j = 0 ... bins)
/// and the bins of a coordinate, guessed with one multiply and corrected against the planes.
struct SpatialBins {
    float pl[SahBins::max_bins + 1];  ///< The planes, pl[j] = spatial_plane(box, a, j, bins).
    float lo;            ///< The box's low plane on the axis.
    float scale;         ///< Bins per unit of the axis.
    std::uint32_t bins;  ///< Bins on the axis.
    /// The planes of `box` on axis a (an axis the box has extent on), `bins` <= max_bins.
    SpatialBins(const AABB<float>& box, int a, std::uint32_t n)
        : lo(box.lo[a]), scale(float(n) / (box.hi[a] - box.lo[a])), bins(n) {
        for (std::uint32_t j = 0; j <= bins; ++j) pl[j] = spatial_plane(box, a, j, bins);
    }
    /// The last bin whose low plane is <= x (a reference with lo = x starts there).
    std::uint32_t from(float x) const {
        std::uint32_t j = guess(x);
        while (j > 0 && pl[j] > x) --j;
        while (j + 1 < bins && pl[j + 1] <= x) ++j;
        return j;
    }
    /// The first bin whose high plane is >= x (a reference with hi = x ends there).
    std::uint32_t to(float x) const {
        std::uint32_t j = guess(x);
        while (j + 1 < bins && pl[j + 1] < x) ++j;
        while (j > 0 && pl[j] >= x) --j;
        return j;
    }
    /// A bin near x, the loops above correct it.
    std::uint32_t guess(float x) const {
        return std::uint32_t(std::min(float(bins - 1), std::max(0.0f, (x - lo) * scale)));
    }
};

/// The cheapest object split on axis a, if cheaper than `best` (Wald 2007, §3.2: suffix
/// costs right to left, then prefixes left to right), over the m bins that hold references
/// (SahBins::axis): a boundary next to an empty bin costs what the one before it does, and
/// the first of equal costs is kept, as a sweep over every boundary (BinnedSah::sweep) keeps it.
inline void sweep_bins(const SahCosts& cost, int a, const AABB<float>* box, const std::uint32_t* count,
                       const std::uint32_t* bin, std::uint32_t m, float inv_area, SahSplit& best) {
    if (m < 2) return;
    float right_cost[SahBins::max_bins];
    std::uint32_t right_n[SahBins::max_bins];
    AABB<float> acc;
    std::uint32_t cnt = 0;
    for (std::uint32_t t = m - 1; t > 0; --t) {
        acc.extend(box[t]);
        cnt += count[t];
        right_n[t] = cnt;
        right_cost[t] = acc.surface_area() * float(cost.blocks(cnt));
    }
    acc = AABB<float>{};
    cnt = 0;
    std::uint32_t won = 0;
    for (std::uint32_t t = 1; t < m; ++t) {
        acc.extend(box[t - 1]);
        cnt += count[t - 1];
        const float c = cost.traversal +
                        cost.intersection * (acc.surface_area() * float(cost.blocks(cnt)) + right_cost[t]) * inv_area;
        if (c < best.cost) best = SahSplit{a, bin[t - 1] + 1, c, acc, {}, cnt, right_n[t]}, won = t;
    }
    for (std::uint32_t t = won; won && t < m; ++t) best.right.extend(box[t]);
}

/// Partitions refs[b, e): those whose centre's bin on `axis` is below `bin` first, each side
/// in its order, through scratch[b, e) (a side per reference chosen without a branch: which
/// side is as good as random), and gives the centre boxes of both sides. Returns the first
/// reference of the right side.
inline std::uint32_t partition_by_bin(BvhRef* refs, BvhRef* scratch, std::uint32_t b, std::uint32_t e,
                                      const BinMap& map, int axis, std::uint32_t bin, AABB<float>& left_cbox,
                                      AABB<float>& right_cbox) {
    const Float4 up = Float4::splat(infinity<float>), down = Float4::splat(-infinity<float>);
    Float4 llo = up, lhi = down, rlo = up, rhi = down;
    BvhRef* l = scratch + b;
    BvhRef* r = scratch + e;  // the right side, written from the end backwards
    for (std::uint32_t i = b; i < e; ++i) {
        const Float4 c = BinMap::centre(refs[i]);
        const bool f = map.below(c, axis, bin);
        *(f ? l : r - 1) = refs[i];
        l += f;
        r -= !f;
        llo = min(llo, Float4::select(f, c, up)), lhi = max(lhi, Float4::select(f, c, down));
        rlo = min(rlo, Float4::select(f, up, c)), rhi = max(rhi, Float4::select(f, down, c));
    }
    const auto m = std::uint32_t(l - scratch);
    std::copy(scratch + b, l, refs + b);
    std::reverse_copy(r, scratch + e, refs + m);
    left_cbox = {llo.xyz(), lhi.xyz()};
    right_cbox = {rlo.xyz(), rhi.xyz()};
    return m;
}

}  // namespace detail

}  // namespace glint
