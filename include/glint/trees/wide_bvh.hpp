// glint/trees/wide_bvh.hpp: the wide (4- or 8-ary) BVH, its nodes and its traversal, for
// any primitives: the leaf test is the caller's callable.
//
// Collapse: the binned SAH binary tree (bvh_builder.hpp) becomes N-wide by the collapse of
// least SAH cost (Ylitie, Karras, Laine 2017; detail::WideCollapse), chosen by dynamic
// programming over the binary nodes: which binary subtrees become a wide node's children,
// and which become one leaf. (Wald, Benthin, Boulos, "Getting rid of packets", 2008,
// Dammertz, Hanika, Keller, "Shallow bounding volume hierarchies", 2008, and Ernst and
// Greiner, "Multi bounding volume hierarchies", 2008, introduced N-ary BVHs for single rays.)
//
// Nodes: the N child boxes structure-of-arrays, one array of N floats per box plane, so that
// one step tests every child with a few SIMD instructions (AVX for N = 8, SSE for N = 4, a
// portable loop otherwise and on request; all three compute the same floats).
//
// Traversal: children whose box the ray enters are visited nearest first; the others go on
// a stack with their entry distance and are dropped when popped beyond the closest hit.
// The slab test is conservative (Ize, "Robust BVH Ray Traversal", JCGT 2013): the exit
// distance is enlarged by 1 + 2 gamma_3 (the bound on the rounding of (plane - o) / d), so
// a box the ray meets is never rejected by rounding; for an interval starting below 0
// (tmin < 0), whose boxes behind the origin have negative distances, both ends are moved
// outward instead (wide_lower, wide_upper); a NaN slab distance (a ray lying in a
// box face) constrains nothing. Rays with NaN or infinite coordinates, a zero direction or
// an interval that is not ordered (tmin <= tmax, false for a NaN) hit nothing.
//
// Thread safety: traversal is const and keeps its state on the caller's stack; any number
// of threads may query one tree at once.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <deque>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#if defined(__SSE2__) || defined(__AVX__)
#include <immintrin.h>
#endif

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/intersection/triangle_leaves.hpp>
#include <glint/trees/bvh_builder.hpp>

namespace glint {

/// One N-wide node: bounds[2a][i] and bounds[2a + 1][i] are the low and high planes of child
/// i on axis a (an unused child: low +inf, high -inf, which no ray enters); child[i] is an
/// inner node's index or a leaf reference (wide_leaf_*).
template <int N>
struct alignas(N * 4) WideBvhNode {
    float bounds[6][N];
    std::uint32_t child[N];
};

/// How a wide node stores its child boxes: as floats, or quantized to 8 bits per plane
/// relative to the node's own box (Ylitie, Karras, Laine, "Efficient incoherent ray traversal
/// on GPUs through compressed wide BVHs", HPG 2017; Embree's compressed nodes).
enum class WideBoxes { floats, quantized };

/// One N-wide node with quantized child boxes: child i's low and high planes on axis a are
/// origin[a] + q[2a][i] * s_a and origin[a] + q[2a + 1][i] * s_a, s_a = 2^(exp[a] - 127) (the
/// float whose exponent bits are exp[a]); the product is exact, so the decoded plane is one
/// rounded addition, which the build checks: the decoded box always contains the child's
/// box (low planes rounded down, high planes up), so no hit is lost. Children 0 ... count - 1
/// are in use. 96 bytes for N = 8 (two cache lines), 64 for N = 4.
template <int N>
struct alignas(32) WideBvhQNode {
    float origin[3];
    std::uint8_t exp[3];
    std::uint8_t count;
    std::uint8_t q[6][N];
    std::uint32_t child[N];
};

namespace detail {

/// The decoded plane of a quantized node (build and every traversal path compute it so).
inline float wide_scale(std::uint8_t e) { return std::bit_cast<float>(std::uint32_t(e) << 23); }
inline float wide_plane(float origin, std::uint8_t q, float scale) { return origin + float(q) * scale; }

/// Quantizes one axis of a node: the scale (a power of two) is the smallest whose 255 steps
/// from the node's low plane reach its high plane after rounding; each child plane is
/// rounded outward, then moved a step further while the decoded plane falls inside the box.
template <int N>
void wide_quantize_axis(const WideBvhNode<N>& f, int a, WideBvhQNode<N>& q) {
    const int k = q.count;
    float lo = infinity<float>, hi = -infinity<float>;
    for (int i = 0; i < k; ++i) {
        lo = std::min(lo, f.bounds[2 * a][i]);
        hi = std::max(hi, f.bounds[2 * a + 1][i]);
    }
    int ex = 0;  // (hi - lo) / 255 < 2^ex: start there, then fix the rounding up
    std::frexp((hi - lo) / 255.0f, &ex);
    int e = std::clamp(ex + 126, 27, 254);  // >= 2^-100: q * s stays a normal float, so the product is exact
    while (e < 254 && wide_plane(lo, 255, wide_scale(std::uint8_t(e))) < hi) ++e;
    const float s = wide_scale(std::uint8_t(e));
    q.origin[a] = lo;
    q.exp[a] = std::uint8_t(e);
    for (int i = 0; i < k; ++i) {
        const float bl = f.bounds[2 * a][i], bh = f.bounds[2 * a + 1][i];
        int ql = int(std::clamp(std::floor((bl - lo) / s), 0.0f, 255.0f));
        int qh = int(std::clamp(std::ceil((bh - lo) / s), 0.0f, 255.0f));
        while (ql > 0 && wide_plane(lo, std::uint8_t(ql), s) > bl) --ql;
        while (qh < 255 && wide_plane(lo, std::uint8_t(qh), s) < bh) ++qh;
        q.q[2 * a][i] = std::uint8_t(ql);
        q.q[2 * a + 1][i] = std::uint8_t(qh);
    }
}

/// The quantized form of a float node whose used children come first.
template <int N>
WideBvhQNode<N> wide_quantize(const WideBvhNode<N>& f) {
    WideBvhQNode<N> q{};
    while (q.count < N && !(f.bounds[0][q.count] > f.bounds[1][q.count])) ++q.count;  // unused: low +inf, high -inf
    for (int a = 0; a < 3; ++a) wide_quantize_axis(f, a, q);
    for (int i = 0; i < N; ++i) q.child[i] = f.child[i];
    return q;
}

/// The float node whose boxes a quantized node stands for (unused children: no box).
template <int N>
WideBvhNode<N> wide_decode(const WideBvhQNode<N>& n) {
    WideBvhNode<N> f;
    for (int r = 0; r < 6; ++r)
        for (int i = 0; i < N; ++i)
            f.bounds[r][i] = i < n.count ? wide_plane(n.origin[r / 2], n.q[r][i], wide_scale(n.exp[r / 2]))
                                         : (r % 2 ? -infinity<float> : infinity<float>);
    for (int i = 0; i < N; ++i) f.child[i] = n.child[i];
    return f;
}

/// Leaf references: bit 31 set, 4 bits of count - 1 (1 ... 16), 27 bits of first index
/// (all ones is no leaf: an unused child).
inline constexpr std::uint32_t wide_leaf_bit = 0x80000000u;
inline constexpr std::uint32_t wide_max_first = (1u << 27) - 2u;
inline bool wide_is_leaf(std::uint32_t ref) { return (ref & wide_leaf_bit) != 0; }
inline std::uint32_t wide_leaf_first(std::uint32_t ref) { return ref & ((1u << 27) - 1u); }
inline std::uint32_t wide_leaf_count(std::uint32_t ref) { return ((ref >> 27) & 15u) + 1u; }
inline std::uint32_t wide_leaf(std::uint32_t first, std::uint32_t count) {
    if (first > wide_max_first || count < 1 || count > 16)
        throw Error("WideBvh: leaf (first " + std::to_string(first) + ", count " + std::to_string(count) +
                    ") does not fit a reference (first < 2^27, count 1 ... 16)");
    return wide_leaf_bit | ((count - 1) << 27) | first;
}

/// 1 + 2 gamma_3 rounded up, gamma_n = n u / (1 - n u), u = 2^-24 (Ize 2013; pbrt-v3 3.9).
inline constexpr float wide_exit_scale = 1.0f + 2.0f * (3.0f * 0x1p-24f / (1.0f - 3.0f * 0x1p-24f)) + 0x1p-23f;
/// 1 - (wide_exit_scale - 1), exactly (Sterbenz).
inline constexpr float wide_entry_scale = 2.0f - wide_exit_scale;

/// Ize's enlarged exit distance t1 * wide_exit_scale holds for t1 >= 0, which every box the
/// ray may enter has when the interval starts at tmin >= 0 (rounding keeps a distance's
/// sign). An interval reaching below 0 (tmin < 0) can enter boxes behind the origin, where
/// that product would shrink a negative exit: a computed distance c (three roundings, within
/// gamma_3 |c| of the true one) is moved away from the box on both ends instead, the entry
/// down to c * (c < 0 ? wide_exit_scale : wide_entry_scale) and the exit up to c * (c < 0 ?
/// wide_entry_scale : wide_exit_scale), each beyond the true distance by more than the
/// product's own rounding.
[[gnu::always_inline]] inline float wide_lower(float c) { return c * (c < 0.0f ? wide_exit_scale : wide_entry_scale); }
[[gnu::always_inline]] inline float wide_upper(float c) { return c * (c < 0.0f ? wide_entry_scale : wide_exit_scale); }
/// An exit distance (or the interval's end) as the test enlarges it.
template <bool Signed>
[[gnu::always_inline]] inline float wide_exit_bound(float t) {
    if constexpr (Signed) return wide_upper(t);
    else return t * wide_exit_scale;
}

/// The per-ray data of the slab test, and the test of one node's N boxes: a bit mask of the
/// children entered within (tmin, tmax), their entry distances in tn.
template <int N, bool Portable, bool Signed = false>
struct WideBoxTest {
    float o[3], inv[3];
    int near[3], far[3];  // bounds rows of the entry and exit planes per axis

    explicit WideBoxTest(const Ray<float>& r) {
        for (int a = 0; a < 3; ++a) {
            o[a] = r.origin[a];
            inv[a] = 1.0f / r.direction[a];
            const int neg = std::signbit(r.direction[a]) ? 1 : 0;
            near[a] = 2 * a + neg;
            far[a] = 2 * a + 1 - neg;
        }
    }
    unsigned test(const WideBvhNode<N>& n, float tmin, float tmax, float* tn) const {
        unsigned mask = 0;
        for (int i = 0; i < N; ++i) {
            float t0 = tmin, t1 = tmax;
            for (int a = 0; a < 3; ++a) {
                const float tl = (n.bounds[near[a]][i] - o[a]) * inv[a];
                const float th = (n.bounds[far[a]][i] - o[a]) * inv[a];
                t0 = tl > t0 ? tl : t0;  // max, keeping t0 for a NaN slab (as maxps)
                t1 = th < t1 ? th : t1;
            }
            if constexpr (Signed) t0 = wide_lower(t0);
            tn[i] = t0;
            mask |= unsigned(t0 <= wide_exit_bound<Signed>(t1)) << i;
        }
        return mask;
    }
    /// Quantized nodes: the planes decoded (the AVX2 path computes the same floats).
    unsigned test(const WideBvhQNode<N>& n, float tmin, float tmax, float* tn) const {
        return test(wide_decode(n), tmin, tmax, tn);
    }
};

#if defined(__AVX__)
/// 8-wide nodes with AVX: the same operations as the portable loop, in the same order.
template <bool Signed>
struct WideBoxTest<8, false, Signed> {
    __m256 o[3], inv[3];
    std::size_t near[3], far[3];  // byte offsets of the rows in a node

    [[gnu::always_inline]] explicit WideBoxTest(const Ray<float>& r) {
        // 1 / d for the three axes with one division (the same correctly rounded quotients).
        alignas(16) float q[4];
        _mm_store_ps(q, _mm_div_ps(_mm_set1_ps(1.0f), _mm_setr_ps(r.direction.x, r.direction.y, r.direction.z, 1.0f)));
        for (int a = 0; a < 3; ++a) {
            o[a] = _mm256_set1_ps(r.origin[a]);
            inv[a] = _mm256_set1_ps(q[a]);
            const std::size_t neg = std::signbit(r.direction[a]) ? 1 : 0;
            near[a] = (2 * std::size_t(a) + neg) * sizeof(__m256);
            far[a] = (2 * std::size_t(a) + 1 - neg) * sizeof(__m256);
        }
    }
    [[gnu::always_inline]] unsigned test(const WideBvhNode<8>& n, float tmin, float tmax, float* tn) const {
        __m256 t0 = _mm256_set1_ps(tmin), t1 = _mm256_set1_ps(tmax);
        const char* rows = reinterpret_cast<const char*>(n.bounds);
        for (int a = 0; a < 3; ++a) {
            const __m256 tl = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(reinterpret_cast<const float*>(rows + near[a])), o[a]), inv[a]);
            const __m256 th = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(reinterpret_cast<const float*>(rows + far[a])), o[a]), inv[a]);
            t0 = _mm256_max_ps(tl, t0);  // tl > t0 ? tl : t0
            t1 = _mm256_min_ps(th, t1);  // th < t1 ? th : t1
        }
        return finish(t0, t1, tn);
    }
#if defined(__AVX2__)
    [[gnu::always_inline]] unsigned test(const WideBvhQNode<8>& n, float tmin, float tmax, float* tn) const {
        __m256 t0 = _mm256_set1_ps(tmin), t1 = _mm256_set1_ps(tmax);
        const char* rows = reinterpret_cast<const char*>(n.q);
        auto plane = [&](std::size_t row_offset, __m256 origin, __m256 scale) {  // the float row offset / 4
            const __m128i q = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(rows + row_offset / 4));
            return _mm256_add_ps(origin, _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(q)), scale));
        };
        for (int a = 0; a < 3; ++a) {
            const __m256 org = _mm256_broadcast_ss(&n.origin[a]), s = _mm256_set1_ps(wide_scale(n.exp[a]));
            const __m256 tl = _mm256_mul_ps(_mm256_sub_ps(plane(near[a], org, s), o[a]), inv[a]);
            const __m256 th = _mm256_mul_ps(_mm256_sub_ps(plane(far[a], org, s), o[a]), inv[a]);
            t0 = _mm256_max_ps(tl, t0);
            t1 = _mm256_min_ps(th, t1);
        }
        const unsigned used = (1u << n.count) - 1u;
        return finish(t0, t1, tn) & used;
    }
#else
    unsigned test(const WideBvhQNode<8>& n, float tmin, float tmax, float* tn) const {
        return test(wide_decode(n), tmin, tmax, tn);
    }
#endif

private:
    /// Entry distances to tn, and the mask of children entered (the portable test's ends).
    [[gnu::always_inline]] unsigned finish(__m256 t0, __m256 t1, float* tn) const {
        const __m256 up = _mm256_set1_ps(wide_exit_scale), down = _mm256_set1_ps(wide_entry_scale);
        if constexpr (Signed) {  // blendv picks its second operand where the sign bit is set
            t0 = _mm256_mul_ps(t0, _mm256_blendv_ps(down, up, t0));
            t1 = _mm256_mul_ps(t1, _mm256_blendv_ps(up, down, t1));
        } else {
            t1 = _mm256_mul_ps(t1, up);
        }
        _mm256_storeu_ps(tn, t0);
        return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ)));
    }
};
#endif

#if defined(__SSE2__)
/// 4-wide nodes with SSE.
template <bool Signed>
struct WideBoxTest<4, false, Signed> {
    __m128 o[3], inv[3];
    int near[3], far[3];

    explicit WideBoxTest(const Ray<float>& r) {
        const WideBoxTest<4, true> s(r);
        for (int a = 0; a < 3; ++a) {
            o[a] = _mm_set1_ps(s.o[a]);
            inv[a] = _mm_set1_ps(s.inv[a]);
            near[a] = s.near[a];
            far[a] = s.far[a];
        }
    }
    unsigned test(const WideBvhNode<4>& n, float tmin, float tmax, float* tn) const {
        __m128 t0 = _mm_set1_ps(tmin), t1 = _mm_set1_ps(tmax);
        for (int a = 0; a < 3; ++a) {
            const __m128 tl = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n.bounds[near[a]]), o[a]), inv[a]);
            const __m128 th = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n.bounds[far[a]]), o[a]), inv[a]);
            t0 = _mm_max_ps(tl, t0);
            t1 = _mm_min_ps(th, t1);
        }
        const __m128 up = _mm_set1_ps(wide_exit_scale), down = _mm_set1_ps(wide_entry_scale);
        if constexpr (Signed) {  // -0 takes the scale of +0, as in the portable test (either keeps -0)
            const __m128 n0 = _mm_cmplt_ps(t0, _mm_setzero_ps()), n1 = _mm_cmplt_ps(t1, _mm_setzero_ps());
            t0 = _mm_mul_ps(t0, _mm_or_ps(_mm_and_ps(n0, up), _mm_andnot_ps(n0, down)));
            t1 = _mm_mul_ps(t1, _mm_or_ps(_mm_and_ps(n1, down), _mm_andnot_ps(n1, up)));
        } else {
            t1 = _mm_mul_ps(t1, up);
        }
        _mm_storeu_ps(tn, t0);
        return unsigned(_mm_movemask_ps(_mm_cmple_ps(t0, t1)));
    }
    unsigned test(const WideBvhQNode<4>& n, float tmin, float tmax, float* tn) const {
        return test(wide_decode(n), tmin, tmax, tn);
    }
};
#endif

/// Whether traversal can give the ray any hit (see the file comment): x * 0 is 0 for a
/// finite x and NaN otherwise, so one comparison checks all six coordinates.
[[gnu::always_inline]] inline bool wide_ray_valid(const Ray<float>& r) {
    const Vec3f& o = r.origin;
    const Vec3f& d = r.direction;
    const float z = (o.x * 0.0f + o.y * 0.0f) + (o.z * 0.0f + d.x * 0.0f) + (d.y * 0.0f + d.z * 0.0f);
    return (z == 0.0f) & ((d.x != 0.0f) | (d.y != 0.0f) | (d.z != 0.0f)) & (r.tmin <= r.tmax);
}

}  // namespace detail

/// A leaf callable for WideBvh::intersect: the trees' LeafTest (triangle_leaves.hpp).
template <class F>
concept WideLeafTest = LeafTest<F>;

/// What one or more queries did (for measurements): nodes whose children were tested, and
/// leaves and records (lanes of padded batches) tested.
struct WideBvhCounters {
    std::uint64_t nodes = 0, leaves = 0, records = 0;
};

/// Accounting of a wide BVH (node count and bytes, depth, leaves).
struct WideBvhStats {
    std::size_t nodes = 0, leaves = 0, node_bytes = 0;
    std::uint32_t depth = 0;  // wide levels on the longest path, leaves included
    // The collapse's SAH cost per ray entering the root's box (WideCollapse) with the float
    // boxes (quantized ones round them outward); 0 for a one-leaf tree or a root box of no area.
    float sah_cost = 0;
};

namespace detail {
/// The collapse of a binary SAH tree into an N-wide one that minimizes the wide tree's SAH
/// cost (Ylitie, Karras, Laine 2017, section 3.1), by dynamic programming over the binary
/// nodes. A binary subtree s fills one or more child slots of a wide node; as one slot it
/// is a wide leaf (the whole subtree's primitives, at most max_leaf of them, costing C_I per
/// started block of leaf_block) or a wide node (C_N, BvhBuildOptions::wide_node_cost, then
/// its children, in 2 ... N slots); every cost is weighted by the surface area of its box,
/// the SAH's estimate of the rays that enter it. cost(s, i), s in at most i slots, is the
/// cheapest of s in i - 1 slots and of i slots shared between s's two children; equal
/// costs go to fewer wide nodes. The solution is read back top-down. Unlike opening
/// children greedily by area, this fills nodes whose children would otherwise be few, and
/// merges small sibling leaves into one.
template <int N>
class WideCollapse {
public:
    /// Solves the collapse of binary tree `bin`, whose root is an inner node.
    WideCollapse(const BinaryBvh& bin, const BvhBuildOptions& opt) : bin_(bin), at_(bin.nodes.size()) { solve(0, opt); }
    /// Binary subtree s, placed in one slot: a wide leaf (or else a wide node).
    bool is_leaf(std::uint32_t s) const { return at_[s].leaf; }
    /// The children of the wide node made of binary inner node s; returns how many (2 ... N).
    int children(std::uint32_t s, std::uint32_t* kids) const {
        int k = 0;
        place(s + 1, at_[s].node_left, kids, k);
        place(bin_.nodes[s].right, at_[s].node_slots - at_[s].node_left, kids, k);
        return k;
    }
    /// The SAH cost of the whole wide tree (binary node 0 as the root's wide node) per ray
    /// entering the root's box.
    double root_cost() const { return root_cost_; }

private:
    struct Slot {                 // the decisions for binary subtree s (its costs live on the stack)
        std::uint8_t left[N];     // s in at most i slots (index i - 1): 0 = as in i - 1, else the left child's slots
        bool leaf = true;         // s in one slot: a wide leaf, else a wide node
        std::uint8_t node_left = 0, node_slots = 0;  // s as a wide node: its children's slots
    };
    /// A subtree's cost, and its wide nodes to break ties: where boxes have no area (points,
    /// segments) every cost is 0, and the fewest nodes keep the tree full and shallow.
    struct Cost {
        double sah = 0;
        std::uint32_t nodes = 0;
        Cost operator+(const Cost& o) const { return {sah + o.sah, nodes + o.nodes}; }
        bool operator<(const Cost& o) const { return sah < o.sah || (sah == o.sah && nodes < o.nodes); }
    };
    using Costs = std::array<Cost, N>;  // s in at most 1 ... N slots

    /// The costs of subtree s, after its children's (post-order; recursion as deep as the tree).
    Costs solve(std::uint32_t s, const BvhBuildOptions& opt) {
        const BinaryBvhNode& b = bin_.nodes[s];
        Slot& o = at_[s];
        // In double: finite for every finite float box (a float area overflows from
        // coordinates of about 10^19).
        const double area = AABB<double>{Vec3<double>(b.box.lo), Vec3<double>(b.box.hi)}.surface_area();
        const Cost leaf{b.leaf() || b.count <= opt.max_leaf ? opt.intersection_cost * double(opt.blocks(b.count)) * area
                                                            : infinity<double>,
                        0};
        Costs cost;
        cost.fill(leaf);
        std::fill(o.left, o.left + N, std::uint8_t(0));
        if (b.leaf()) return cost;
        const Costs l = solve(s + 1, opt), r = solve(b.right, opt);
        Cost shared[N + 1];  // the cheapest sharing of exactly i slots between the children
        std::uint8_t shared_left[N + 1];
        Cost node{infinity<double>, 0};
        for (int i = 2; i <= N; ++i) {
            shared[i] = l[0] + r[i - 2], shared_left[i] = 1;
            for (int k = 2; k < i; ++k)
                if (const Cost c = l[k - 1] + r[i - k - 1]; c < shared[i]) shared[i] = c, shared_left[i] = std::uint8_t(k);
            if (shared[i] < node) node = shared[i], o.node_slots = std::uint8_t(i), o.node_left = shared_left[i];
        }
        node = node + Cost{opt.wide_node_cost * area, 1};
        if (s == 0) root_cost_ = area > 0 ? node.sah / area : 0;  // a root box of no area: no rays
        o.leaf = !(node < leaf);
        cost[0] = o.leaf ? leaf : node;
        for (int i = 2; i <= N; ++i) {
            cost[i - 1] = cost[i - 2];
            if (shared[i] < cost[i - 1]) cost[i - 1] = shared[i], o.left[i - 1] = shared_left[i];
        }
        return cost;
    }
    /// Appends the slots binary subtree s takes when it may take i of them.
    void place(std::uint32_t s, int i, std::uint32_t* kids, int& k) const {
        while (i > 1 && at_[s].left[i - 1] == 0) --i;
        if (i == 1) {
            kids[k++] = s;
            return;
        }
        const int left = at_[s].left[i - 1];
        place(s + 1, left, kids, k);
        place(bin_.nodes[s].right, i - left, kids, k);
    }

    const BinaryBvh& bin_;  // outlives the collapse: both live in WideBvh's constructor
    std::vector<Slot> at_;
    double root_cost_ = 0;
};
}  // namespace detail

/// A wide node layout policy: where the nodes of a collapsed wide BVH go in its node array.
/// `arrange<N>(nodes)` gets the nodes in the collapse's order (root first; a child word
/// without the leaf bit is an inner child's index) and returns every node's new index (a
/// permutation keeping the root at 0); `label()` names it in benchmarks ("" for none).
template <class L>
concept WideNodeLayout = requires(std::span<const WideBvhNode<8>> n8, std::span<const WideBvhNode<4>> n4) {
    { L::label() } -> std::convertible_to<std::string>;
    { L::template arrange<8>(n8) } -> std::same_as<std::vector<std::uint32_t>>;
    { L::template arrange<4>(n4) } -> std::same_as<std::vector<std::uint32_t>>;
};

/// The collapse's own order (BvhBuildOptions::node_order: depth first or sibling blocks).
struct WideBuildOrder {
    static std::string label() { return ""; }
    template <int N>
    static std::vector<std::uint32_t> arrange(std::span<const WideBvhNode<N>> nodes) {
        std::vector<std::uint32_t> at(nodes.size());
        for (std::size_t i = 0; i < at.size(); ++i) at[i] = std::uint32_t(i);
        return at;
    }
};

/// 000's compact subtrees (000 §4.4; layouts.hpp's CompactSubtrees)
/// on wide nodes: the nodes are stored in units of at most K consecutive nodes, each holding
/// whole subtrees (K = 18 eight-wide nodes of 224 bytes fill 4 KiB, a page; K = 9 is a node
/// and its eight children). A subtree starts with the root or with a sibling block (the
/// inner children of one node, side by side) and grows breadth first: each node met adds
/// its inner children as one block while the unit has room; a block that does not fit
/// waits in a queue (breadth first between subtrees, as in layouts.hpp, where the pointer
/// level of a subtree leads to fresh ones; here the parent's child words are the
/// pointers). A waiting block starts a fresh unit, or, while the current unit has room for
/// it, continues there: 000's reuse of the room a branch that ended early left.
/// Child words stay explicit indices: a wide node keeps one word per child for its leaves'
/// references anyway, so 000's implicit addressing inside a subtree would save only the
/// words of inner children (4 of 224 bytes per node, 8 wide) at the price of a second node
/// format; node bytes equal the collapse's order (nothing is padded).
template <std::uint32_t K>
struct WideCompactSubtrees {
    static std::string label() { return "compact" + std::to_string(K); }
    template <int N>
    static std::vector<std::uint32_t> arrange(std::span<const WideBvhNode<N>> nodes) {
        static_assert(K >= std::uint32_t(N), "WideCompactSubtrees: a unit holds at least one sibling block");
        std::vector<std::uint32_t> at(nodes.size(), 0), subtree{0}, block;
        std::deque<std::uint32_t> waiting;  // nodes whose inner children did not fit their unit
        std::uint32_t next = 1, unit = 1;   // the root stays at 0; nodes in the current unit
        auto place_children = [&](std::uint32_t p) {
            block.clear();
            for (std::uint32_t c : nodes[p].child)
                if (!detail::wide_is_leaf(c)) block.push_back(c);
            for (std::uint32_t c : block) at[c] = next++;
            unit += std::uint32_t(block.size());
        };
        auto inner_count = [&](std::uint32_t p) {
            std::uint32_t k = 0;
            for (std::uint32_t c : nodes[p].child) k += !detail::wide_is_leaf(c);
            return k;
        };
        for (;;) {
            for (std::size_t q = 0; q < subtree.size(); ++q) {  // grows while it is read
                const std::uint32_t k = inner_count(subtree[q]);
                if (k == 0) continue;
                if (unit + k > K) {
                    waiting.push_back(subtree[q]);
                    continue;
                }
                place_children(subtree[q]);
                subtree.insert(subtree.end(), block.begin(), block.end());
            }
            if (waiting.empty()) return at;
            if (unit + inner_count(waiting.front()) > K) unit = 0;  // a fresh unit
            place_children(waiting.front());
            waiting.pop_front();
            subtree = block;
        }
    }
};

/// N-wide BVH (N = 4 or 8) over primitive boxes, child boxes stored as B says, nodes
/// arranged in memory by layout policy L; leaves are ranges of prims(), or of whatever
/// remap_leaves() made them.
template <int N, WideBoxes B = WideBoxes::floats, WideNodeLayout L = WideBuildOrder>
class WideBvh {
    static_assert(N == 4 || N == 8, "WideBvh: 4- or 8-wide nodes");
    using FloatNodes = std::vector<WideBvhNode<N>, detail::CacheLineAllocator<WideBvhNode<N>>>;

public:
    using Node = std::conditional_t<B == WideBoxes::floats, WideBvhNode<N>, WideBvhQNode<N>>;
    static constexpr int width = N;
    static constexpr WideBoxes box_format = B;
    static constexpr const char* boxes_label = B == WideBoxes::floats ? "soa" : "soa-q8";
    /// The benchmarks' layout column: the box format, then L's label if any.
    static std::string layout_label() { return L::label().empty() ? boxes_label : boxes_label + ("-" + L::label()); }
    /// Stack entries: a step pushes at most N - 1 more than it pops, so a tree of depth D
    /// needs (N - 1) D + 1; build() refuses deeper trees.
    static constexpr int max_stack = 512;

    WideBvh() = default;
    /// Over boxes[i] for every i whose box is not empty and finite; `clip` chops primitives
    /// for spatial splits (build_binary_bvh).
    template <PrimitiveClipper Clip = NoClipper>
    explicit WideBvh(std::span<const AABB<float>> boxes, const BvhBuildOptions& opt = {}, const Clip& clip = {}) {
        const BinaryBvh bin = build_binary_bvh(boxes, opt, clip);
        prims_ = bin.prims;
        order_ = opt.node_order;
        if (bin.empty()) return;
        FloatNodes wide;
        wide.emplace_back(empty_node());
        stats_.depth = 1;
        if (bin.nodes[0].leaf()) {  // a one-leaf tree: a root with one child
            set_child(wide[0], 0, bin.nodes[0], detail::wide_leaf(bin.nodes[0].begin, bin.nodes[0].count));
            stats_.leaves = 1;
        } else {
            const detail::WideCollapse<N> collapse(bin, opt);
            stats_.sah_cost = float(collapse.root_cost());
            fill(bin, collapse, wide, 0, 0, 1);
        }
        if constexpr (!std::same_as<L, WideBuildOrder>) arrange(wide);
        if constexpr (B == WideBoxes::floats) {
            nodes_ = std::move(wide);
        } else {
            nodes_.reserve(wide.size());
            for (const WideBvhNode<N>& f : wide) nodes_.push_back(detail::wide_quantize(f));
        }
        stats_.nodes = nodes_.size();
        stats_.node_bytes = nodes_.size() * sizeof(Node);
        if ((N - 1) * stats_.depth + 1 > std::uint32_t(max_stack))
            throw Error("WideBvh: depth " + std::to_string(stats_.depth) + " needs more than " +
                        std::to_string(max_stack) + " stack entries");
    }

    /// Primitive order: leaf (first, count) covers prims()[first ... first + count - 1].
    const std::vector<std::uint32_t>& prims() const { return prims_; }
    const std::vector<Node, detail::CacheLineAllocator<Node>>& nodes() const { return nodes_; }
    const WideBvhStats& stats() const { return stats_; }

    /// Replaces every leaf's (first, count) by f(first, count) (a pair), e.g. to point
    /// leaves at records laid out in leaf order. Leaves are visited in node order.
    template <class F>
    void remap_leaves(F&& f) {
        for (Node& n : nodes_)
            for (int i = 0; i < N; ++i)
                if (n.child[i] != empty_ref && detail::wide_is_leaf(n.child[i])) {
                    const auto [first, count] = f(detail::wide_leaf_first(n.child[i]), detail::wide_leaf_count(n.child[i]));
                    n.child[i] = detail::wide_leaf(first, count);
                }
    }

    /// Closest (Any = false) or any hit: `leaf(first, count)` is called for the leaves the
    /// ray enters, nearest first; it lowers ray.tmax to each hit it finds (closest hit).
    /// Portable = true forces the portable box test (the same hits, for tests).
    /// With `counters`, counts the nodes and leaves visited.
    template <bool Any, bool Portable = false, WideLeafTest Leaf>
    [[gnu::always_inline]] bool intersect(Ray<float>& ray, Leaf&& leaf, WideBvhCounters* counters = nullptr) const {
        if (nodes_.empty() || !detail::wide_ray_valid(ray)) return false;
        // Intervals starting below 0 take the box test that widens both ends (see the file
        // comment); the usual ones keep the cheaper test, with no per-node check of which.
        if (ray.tmin < 0.0f) [[unlikely]]
            return traverse<Any, Portable, true>(ray, leaf, counters);
        return traverse<Any, Portable, false>(ray, leaf, counters);
    }

private:
    static constexpr std::uint32_t empty_ref = 0xffffffffu;

    /// intersect() for a valid ray, with the box test for intervals starting below 0 or not.
    template <bool Any, bool Portable, bool Signed, class Leaf>
    [[gnu::always_inline]] bool traverse(Ray<float>& ray, Leaf& leaf, WideBvhCounters* counters) const {
        const detail::WideBoxTest<N, Portable, Signed> box(ray);
        struct Entry {
            std::uint32_t ref;
            float t;
        };
        Entry stack[max_stack];
        int sp = 0;
        bool found = false;
        std::uint32_t ref = 0;
        for (;;) {
            if (!detail::wide_is_leaf(ref)) {
                alignas(32) float tn[N];
                const Node& n = nodes_[ref];
                if (counters) ++counters->nodes;
                unsigned mask = box.test(n, ray.tmin, ray.tmax, tn);
                if (mask != 0) {
                    // The nearest child is visited next without a trip through the stack (as
                    // Embree's BVH-N traversal does); on equal distances the later child first.
                    const int i0 = std::countr_zero(mask);
                    mask &= mask - 1;
                    if (mask == 0) {  // one child
                        ref = n.child[i0];
                        continue;
                    }
                    const int i1 = std::countr_zero(mask);
                    mask &= mask - 1;
                    const bool later = !(tn[i0] < tn[i1]);
                    Entry near{n.child[later ? i1 : i0], tn[later ? i1 : i0]};
                    stack[sp++] = Entry{n.child[later ? i0 : i1], tn[later ? i0 : i1]};
                    prefetch(stack[sp - 1].ref);
                    if (mask == 0) {  // two children: the nearer is read next, without a prefetch
                        ref = near.ref;
                        continue;
                    }
                    const int first = sp - 1;
                    stack[sp++] = near;
                    prefetch(near.ref);
                    for (; mask; mask &= mask - 1) {  // insertion by distance, nearest on top
                        const int i = std::countr_zero(mask);
                        int j = sp++;
                        for (; j > first && stack[j - 1].t < tn[i]; --j) stack[j] = stack[j - 1];
                        stack[j] = Entry{n.child[i], tn[i]};
                        prefetch(n.child[i]);
                    }
                    assert(sp <= max_stack);
                    ref = stack[--sp].ref;  // the nearest: within the interval, no test
                    continue;
                }
            } else if (counters && ++counters->leaves,
                       leaf(detail::wide_leaf_first(ref), detail::wide_leaf_count(ref))) {
                found = true;
                if constexpr (Any) return true;
            }
            do {
                if (sp == 0) return found;
                --sp;
            } while (!Any && !(stack[sp].t <= detail::wide_exit_bound<Signed>(ray.tmax)));
            ref = stack[sp].ref;
        }
    }

    /// Asks for the cache lines of inner node `ref` (a child about to be visited or pushed).
    [[gnu::always_inline]] void prefetch([[maybe_unused]] std::uint32_t ref) const {
#if defined(__SSE2__)
        if (!detail::wide_is_leaf(ref)) {
            const char* p = reinterpret_cast<const char*>(&nodes_[ref]);
            for (std::size_t line = 0; line < sizeof(Node); line += 64) _mm_prefetch(p + line, _MM_HINT_T0);
        }
#endif
    }

    static WideBvhNode<N> empty_node() {
        WideBvhNode<N> n;
        for (int i = 0; i < N; ++i) {
            for (int a = 0; a < 3; ++a) {
                n.bounds[2 * a][i] = infinity<float>;
                n.bounds[2 * a + 1][i] = -infinity<float>;
            }
            n.child[i] = empty_ref;
        }
        return n;
    }
    static void set_child(WideBvhNode<N>& node, int i, const BinaryBvhNode& b, std::uint32_t ref) {
        for (int a = 0; a < 3; ++a) {
            node.bounds[2 * a][i] = b.box.lo[a];
            node.bounds[2 * a + 1][i] = b.box.hi[a];
        }
        node.child[i] = ref;
    }

    /// Moves the nodes where L puts them, checking that L gave a permutation keeping the root.
    static void arrange(FloatNodes& wide) {
        const std::vector<std::uint32_t> at = L::template arrange<N>(std::span<const WideBvhNode<N>>(wide.data(), wide.size()));
        if (at.size() != wide.size())
            throw Error("WideBvh: layout " + L::label() + " placed " + std::to_string(at.size()) + " of " +
                        std::to_string(wide.size()) + " nodes");
        std::vector<char> taken(wide.size(), 0);
        for (std::size_t i = 0; i < at.size(); ++i)
            if (at[i] >= wide.size() || taken[at[i]]++ || (i == 0 && at[0] != 0))
                throw Error("WideBvh: layout " + L::label() + " moves node " + std::to_string(i) + " to " +
                            std::to_string(at[i]) + ", not a permutation of " + std::to_string(wide.size()) +
                            " nodes keeping the root at 0");
        FloatNodes moved(wide.size());
        for (std::size_t i = 0; i < wide.size(); ++i) {
            WideBvhNode<N> n = wide[i];
            for (std::uint32_t& c : n.child)
                if (!detail::wide_is_leaf(c)) c = at[c];
            moved[at[i]] = n;
        }
        wide = std::move(moved);
    }

    /// Fills wide node `node` of `wide` from binary inner node `slot` (depth: of this wide
    /// node) with the children `collapse` chose; they take slots 0 ... k - 1.
    void fill(const BinaryBvh& bin, const detail::WideCollapse<N>& collapse, FloatNodes& wide, std::uint32_t slot,
              std::uint32_t node, std::uint32_t depth) {
        std::uint32_t kids[N];
        const int k = collapse.children(slot, kids);
        stats_.depth = std::max(stats_.depth, depth + 1);  // its leaves, at least
        std::uint32_t first_child = 0;
        for (int i = 0; i < k; ++i) {
            const BinaryBvhNode& c = bin.nodes[kids[i]];
            if (collapse.is_leaf(kids[i])) {
                set_child(wide[node], i, c, detail::wide_leaf(c.begin, c.count));
                ++stats_.leaves;
                continue;
            }
            const std::uint32_t child = std::uint32_t(wide.size());
            if (first_child == 0) first_child = child;
            wide.emplace_back(empty_node());
            set_child(wide[node], i, c, child);
            if (order_ == WideNodeOrder::depth_first) fill(bin, collapse, wide, kids[i], child, depth + 1);
        }
        if (order_ == WideNodeOrder::sibling_blocks)  // the inner children were placed side by side
            for (int i = 0; i < k; ++i)
                if (!collapse.is_leaf(kids[i])) fill(bin, collapse, wide, kids[i], first_child++, depth + 1);
    }

    std::vector<Node, detail::CacheLineAllocator<Node>> nodes_;
    std::vector<std::uint32_t> prims_;
    WideNodeOrder order_ = WideNodeOrder::depth_first;
    WideBvhStats stats_;
};

}  // namespace glint
