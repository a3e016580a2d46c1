// glint/trees/wide_node.hpp: the nodes of the wide (4- or 8-ary) BVH: N child boxes
// structure-of-arrays, one array of N floats per box plane, so that one traversal step
// tests every child with a few SIMD instructions (wide_box_test.hpp); or the same boxes
// quantized to 8 bits per plane; the leaf references the child words hold; the tree's
// accounting.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/cache_line_allocator.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>

namespace glint {

/// One N-wide node: bounds[2a][i] and bounds[2a + 1][i] are the low and high planes of child
/// i on axis a (an unused child: low +inf, high -inf, which no ray enters); child[i] is an
/// inner node's index or a leaf reference (wide_leaf_*).
template <int N>
struct alignas(N * 4) WideBvhNode {
    float bounds[6][N];      ///< Child box planes, world space: row 2a low, 2a + 1 high on axis a.
    std::uint32_t child[N];  ///< Inner node index, leaf reference, or all ones for an unused child.
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
    float origin[3];         ///< Low corner of the used children's union (q = 0), world space.
    std::uint8_t exp[3];     ///< Per axis, the exponent bits of the power-of-two step s_a.
    std::uint8_t count;      ///< Children in use, 0 ... N; the rest are unused.
    std::uint8_t q[6][N];    ///< Child planes in steps from origin: row 2a low, 2a + 1 high.
    std::uint32_t child[N];  ///< Inner node index, leaf reference, or all ones for an unused child.
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

/// The child word of an unused child (not a leaf, not a node).
inline constexpr std::uint32_t wide_empty_ref = 0xffffffffu;

/// Float nodes as the collapse and the layouts handle them.
template <int N>
using WideNodes = std::vector<WideBvhNode<N>, CacheLineAllocator<WideBvhNode<N>>>;

/// Stores the float nodes as the tree keeps them: as they are, or quantized.
template <int N>
void wide_store(WideNodes<N>&& wide, WideNodes<N>& out) {
    out = std::move(wide);
}
template <int N>
void wide_store(WideNodes<N>&& wide, std::vector<WideBvhQNode<N>, CacheLineAllocator<WideBvhQNode<N>>>& out) {
    out.reserve(wide.size());
    for (const WideBvhNode<N>& f : wide) out.push_back(wide_quantize(f));
}

}  // namespace detail

/// Accounting of a wide BVH (node count and bytes, depth, leaves).
struct WideBvhStats {
    /// Wide nodes in the tree.
    std::size_t nodes = 0, leaves = 0, node_bytes = 0;  ///< Bytes of the node array.
    /// @var leaves
    /// Leaf references in the child words (each 1 ... 16 primitives).
    std::uint32_t depth = 0;  ///< Wide levels on the longest path, leaves included (0: empty tree).
    /// The collapse's SAH cost per ray entering the root's box (WideCollapse) with the float
    /// boxes (quantized ones round them outward); 0 for a one-leaf tree or a root box of no area.
    float sah_cost = 0;
};

}  // namespace glint
