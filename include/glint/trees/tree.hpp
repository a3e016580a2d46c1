// glint/trees/tree.hpp: the layout-independent built tree shared by the kd-tree and BIH
// builders, the equal-size node formats the layouts encode it into, and the concepts that
// connect builders, layouts and accelerators.
//
// Szécsi 2009, §4.2: a kd-tree splits a cell with one axis-aligned plane into
// two disjoint cells, so a triangle crossing the plane is referenced from both; a BIH
// (bounding interval hierarchy) stores two planes per node, the left child's maximum and the
// right child's minimum along the axis, so every triangle is referenced once and the children
// may overlap or leave a gap. The conclusions for kd-trees carry over to the BIH.
//
// A builder produces a BuiltTree: nodes in depth-first order (a split node is followed by
// its left subtree), each leaf owning a range of `prims` (original triangle indices). The
// layouts (layouts.hpp) then encode this tree into arrays of equal-size nodes.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

/// What kind of binary partitioning tree a builder makes (it decides the node format).
enum class TreeKind : std::uint8_t { kd, bih };

/// One node of a built (not yet encoded) tree.
/// - kd split: `plane[0]` is the split position on `axis`; left child holds x <= plane.
/// - BIH split: `plane[0]` = maximum of the left child's triangles on `axis`,
///   `plane[1]` = minimum of the right child's triangles (may be +-inf for an empty side).
/// - leaf: `prim_begin`, `prim_count` index BuiltTree::prims.
template <class T>
struct BuildNode {
    bool leaf = true;          ///< True for a leaf (the default), false for a split node.
    std::uint8_t axis = 0;     ///< Split axis: 0 = x, 1 = y, 2 = z (split nodes only).
    T plane[2] = {T(0), T(0)}; ///< Split plane(s) on `axis`, world units; kd uses plane[0] only.
    /// Split nodes: index of the left child in BuiltTree::nodes.
    std::uint32_t left = 0, right = 0;  ///< Split nodes: index of the right child in BuiltTree::nodes.
    /// Leaves: first index into BuiltTree::prims.
    std::uint32_t prim_begin = 0, prim_count = 0;  ///< Leaves: triangles in the leaf (0: empty).
};

/// The tree as a builder leaves it, independent of the node layout.
template <class T>
struct BuiltTree {
    TreeKind kind = TreeKind::kd;       ///< Partitioning scheme; decides the node format.
    std::vector<BuildNode<T>> nodes;    ///< Depth-first; nodes[0] is the root.
    std::vector<std::uint32_t> prims;   ///< Leaf contents, original triangle indices.
    AABB<T> bounds;                     ///< Of all (finite) triangles; empty if none.
    std::size_t triangle_count = 0;     ///< Input triangles, including dropped ones.

    /// Number of leaves, empty ones included (O(nodes)).
    std::size_t leaf_count() const {
        std::size_t n = 0;
        for (const auto& nd : nodes) n += nd.leaf;
        return n;
    }
    /// Number of levels (a single leaf has height 1).
    std::uint32_t height(std::uint32_t node = 0) const {
        const BuildNode<T>& n = nodes[node];
        if (n.leaf) return 1;
        return 1 + std::max(height(n.left), height(n.right));
    }
};

/// A builder: a policy that turns triangles into a BuiltTree of its kind, and names the
/// encoded node format its trees are traversed in.
template <class B>
concept TreeBuilder = requires(const B b, std::span<const TriangleVertices<typename B::scalar_type>> tris) {
    typename B::node_type;
    { B::kind } -> std::convertible_to<TreeKind>;
    { b.build(tris) } -> std::same_as<BuiltTree<typename B::scalar_type>>;
};

// ---------------------------------------------------------------------------------------
// Encoded nodes. Szécsi 2009, §4.4: "Every element has the same size, but it
// can be of three different types": a leaf (triangle count and start of its block in the
// leaf list), a splitting node (plane position(s) and axis) and a pointer node (an index to
// another node). glint's nodes describe themselves in the low bits of one 32-bit word:
//   word & 3 in {0, 1, 2}: split node on that axis; word >> 2 is the first child's index
//                          for PointerLayout (unused by the subtree layouts);
//   word & 7 == 3:         leaf; its range in the TriangleStore: word >> 3 = count (0: empty
//                          leaf), the first index in the plane slot's bits; the range counts
//                          groups for intersectors with frames (IVM), records otherwise;
//   word & 7 == 7:         pointer; word >> 3 = index of the node it stands for.
// A kd node is 8 bytes for float (one plane), a BIH node 12 (two planes). Repair: Szécsi 2009 says
// one bit marks a leaf and the position inside the subtree tells pointers from splits; we
// spend one more bit so that traversal needs no position arithmetic to tell them apart.
// ---------------------------------------------------------------------------------------

namespace detail {

/// Unsigned integer of the same size as T, to keep a leaf's first group in a plane slot.
template <class T>
using PlaneBits = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;

template <class T>
T pack_index(std::uint32_t i) {
    return std::bit_cast<T>(static_cast<PlaneBits<T>>(i));
}
template <class T>
std::uint32_t unpack_index(T v) {
    return static_cast<std::uint32_t>(std::bit_cast<PlaneBits<T>>(v));
}

/// Builders leave out triangles that no intersector may hit (the TriangleIntersector
/// contract: degenerate triangles never hit): a non-finite vertex, or zero area (the cross
/// product of two edges is exactly zero in double precision, e.g. a repeated vertex).
template <class T>
bool can_be_hit(const TriangleVertices<T>& t) {
    if (!all_finite(t[0]) || !all_finite(t[1]) || !all_finite(t[2])) return false;
    const Vec3d n = glm::cross(Vec3d(t[1]) - Vec3d(t[0]), Vec3d(t[2]) - Vec3d(t[0]));
    return n.x != 0 || n.y != 0 || n.z != 0;
}

inline constexpr std::uint32_t node_leaf_tag = 3u;
inline constexpr std::uint32_t node_pointer_tag = 7u;
/// Largest index or group count a node word can hold (29 bits).
inline constexpr std::uint32_t node_max_index = (1u << 29) - 1u;

}  // namespace detail

/// Equal-size node with P planes (1 for kd-trees, 2 for BIHs).
template <class T, int Planes>
struct EncodedNode {
    T plane[Planes];     ///< Split: plane position(s); leaf: plane[0]'s bits hold group_begin().
    std::uint32_t word;  ///< Low bits: axis 0-2 (split), 3 (leaf), 7 (pointer); index or count above.

    bool is_split() const { return (word & 3u) != 3u; }  ///< Split node (axis() is valid).
    bool is_leaf() const { return (word & 7u) == detail::node_leaf_tag; }  ///< Leaf, empty or not.
    bool is_pointer() const { return (word & 7u) == detail::node_pointer_tag; }  ///< Pointer node.
    bool is_empty_leaf() const { return word == detail::node_leaf_tag; }  ///< Leaf of 0 groups.
    int axis() const { return static_cast<int>(word & 3u); }  ///< Split nodes: axis 0, 1 or 2.
    std::uint32_t child() const { return word >> 2; }     ///< PointerLayout split nodes: first child's index.
    std::uint32_t target() const { return word >> 3; }    ///< Pointer nodes: the node it stands for.
    std::uint32_t group_count() const { return word >> 3; }  ///< Leaves: groups or records in the range.
    std::uint32_t group_begin() const { return detail::unpack_index<T>(plane[0]); }  ///< Leaves: first one.
    /// Split nodes: where a ray (origin o and inverse direction inv on the node's axis, neg:
    /// the direction's sign bit there) crosses into the near child's side (tn) and out of the
    /// far child's (tf): one plane gives both for a kd node, two planes for a BIH node.
    [[gnu::always_inline]] void distances(T o, T inv, std::uint32_t neg, T& tn, T& tf) const {
        const T tl = (plane[0] - o) * inv, tr = (plane[Planes - 1] - o) * inv;
        tn = neg ? tr : tl;
        tf = neg ? tl : tr;
    }

    /// Split node with b's axis and planes; `child` is stored for PointerLayout (< 2^30).
    static EncodedNode split(const BuildNode<T>& b, std::uint32_t child) {
        EncodedNode n{};
        for (int i = 0; i < Planes; ++i) n.plane[i] = b.plane[i];
        n.word = (child << 2) | b.axis;
        return n;
    }
    /// Leaf over groups [group_begin, group_begin + group_count); count <= detail::node_max_index.
    static EncodedNode leaf(std::uint32_t group_begin, std::uint32_t group_count) {
        EncodedNode n{};
        n.plane[0] = detail::pack_index<T>(group_begin);
        n.word = (group_count << 3) | detail::node_leaf_tag;
        return n;
    }
    /// Pointer node to node index `target` (<= detail::node_max_index).
    static EncodedNode pointer(std::uint32_t target) {
        EncodedNode n{};
        n.word = (target << 3) | detail::node_pointer_tag;
        return n;
    }
};

template <class T> using KdNode = EncodedNode<T, 1>;
template <class T> using BihNode = EncodedNode<T, 2>;

static_assert(sizeof(KdNode<float>) == 8, "kd nodes are 8 bytes for float");
static_assert(sizeof(BihNode<float>) == 12, "BIH nodes are 12 bytes for float");

/// Accounting of an encoded tree (node count, node bytes, wasted slots, bytes per
/// triangle). `slots` is the allocated array length; every slot is one node in size.
struct LayoutStats {
    std::size_t slots = 0;          ///< Allocated nodes (node count).
    std::size_t split_nodes = 0;    ///< Slots holding split nodes.
    std::size_t leaf_nodes = 0;     ///< Slots holding leaves, empty ones included.
    std::size_t pointer_nodes = 0;  ///< Slots holding pointer nodes (subtree layouts only).
    std::size_t wasted_slots = 0;   ///< Allocated but unused (fragmentation).
    std::size_t node_size = 0;      ///< Bytes per node.
    std::size_t triangles = 0;      ///< Input triangles.
    std::size_t node_bytes() const { return slots * node_size; }  ///< Node array size in bytes.
    /// Node memory per input triangle (triangle records are not included: they are the
    /// same for every layout).
    double bytes_per_triangle() const {
        return triangles ? double(node_bytes()) / double(triangles) : 0.0;
    }
};

/// A node layout policy: encodes a BuiltTree into equal-size nodes and tells traversal
/// where a split node's children are (the right child is always first_child + 1).
/// `leaf_groups[i]` is the triangle-store group range of built node i (leaves only).
template <class L>
concept NodeLayout = requires(const BuiltTree<float>& t, std::vector<KdNode<float>>& out,
                              std::span<const std::array<std::uint32_t, 2>> leaf_groups,
                              const KdNode<float>& n, std::uint32_t i) {
    { L::encode(t, leaf_groups, out) } -> std::same_as<LayoutStats>;
    { L::first_child(n, i, i) } -> std::same_as<std::uint32_t>;
    { L::block_base(i) } -> std::same_as<std::uint32_t>;
};

/// A ray accelerator: the interface shared by the trees and the brute-force reference.
/// Every glint accelerator's queries are const and keep their state on the caller's stack
/// (no caches, no counters in the object): any number of threads may query one accelerator
/// at once, as the renderers do.
template <class A>
concept RayAccelerator = requires(const A& a, const Ray<typename A::scalar_type>& r,
                                  StoreHit<typename A::scalar_type>& h) {
    { a.closest_hit(r, h) } -> std::same_as<bool>;
    { a.any_hit(r) } -> std::same_as<bool>;
};

/// A ray accelerator that also answers streams of rays in one call (MeshBvh: packets of 16
/// where the rays are coherent): hits[i] and occluded[i] as the single-ray queries give them,
/// each count the number of hits.
template <class A>
concept StreamAccelerator =
    RayAccelerator<A> && requires(const A& a, std::span<const Ray<typename A::scalar_type>> r,
                                  std::span<StoreHit<typename A::scalar_type>> h, std::span<bool> o) {
        { a.closest_hit(r, h) } -> std::same_as<std::size_t>;
        { a.any_hit(r, o) } -> std::same_as<std::size_t>;
    };

namespace detail {

/// Throws Error naming `query`'s two sizes unless a stream's rays and results are as many.
inline void check_stream(const std::string& query, std::size_t rays, std::size_t results) {
    if (rays != results)
        throw Error(query + ": " + std::to_string(rays) + " rays but " + std::to_string(results) + " results");
}

}  // namespace detail

/// Closest hits of `rays` into `hits` (the same size; a miss leaves its hit as it was) through
/// any accelerator: its stream query where it has one, a ray at a time otherwise. Returns the
/// number of hits; throws Error naming both sizes when they differ.
template <RayAccelerator A>
std::size_t closest_hits(const A& accel, std::span<const Ray<typename A::scalar_type>> rays,
                         std::span<StoreHit<typename A::scalar_type>> hits) {
    if constexpr (StreamAccelerator<A>) {
        return accel.closest_hit(rays, hits);
    } else {
        detail::check_stream("glint::closest_hits", rays.size(), hits.size());
        std::size_t n = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) n += accel.closest_hit(rays[i], hits[i]) ? 1 : 0;
        return n;
    }
}

/// Any hits of `rays` into `occluded` (the same size), as closest_hits() chooses; returns the
/// number occluded.
template <RayAccelerator A>
std::size_t any_hits(const A& accel, std::span<const Ray<typename A::scalar_type>> rays, std::span<bool> occluded) {
    if constexpr (StreamAccelerator<A>) {
        return accel.any_hit(rays, occluded);
    } else {
        detail::check_stream("glint::any_hits", rays.size(), occluded.size());
        std::size_t n = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) n += (occluded[i] = accel.any_hit(rays[i])) ? 1 : 0;
        return n;
    }
}

}  // namespace glint
