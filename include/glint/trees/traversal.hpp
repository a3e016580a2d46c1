// glint/trees/traversal.hpp: the tree accelerator (builder x intersector x layout) and its
// closest-hit and any-hit traversal.
//
// Szécsi 2009, §4.3: starting at the root, at a split node the children are
// labelled near and far by the sign of the ray direction on the split axis; the ray
// segments inside the two cells come from one ray-plane intersection (kd-tree) or two
// (BIH; Szécsi 2009 says "four", counting the GPU BIH's four planes; the node computes
// them, EncodedNode::distances). If only one
// cell has a non-empty segment it is entered; otherwise the far cell and its segment are
// pushed on a stack and the near cell is entered. At a leaf all its triangles are tested
// and the nearest kept; a popped cell whose segment starts beyond the best hit is skipped.
// Repair: the extracted text stops at a leaf "if we have found a suitable hit"; glint
// stops only when the stack holds nothing nearer, which also covers BIH cells that overlap.
//
// Robustness: the segment [t0, t1] starts as the ray's (tmin, tmax) clipped to the
// scene box, so rays starting inside the scene and finite tmin/tmax work unchanged. A cell
// is entered unless its plane distance proves the segment misses it; comparisons are
// written !(t < t0) so that the NaN of a ray parallel to a split plane and lying in it
// ((p - o) * inf with p == o) enters both children, and the +-inf of a parallel ray off the
// plane enters exactly the side the origin is on. Leaves test their triangles over the whole
// ray interval (tmin, best t), never the cell's segment, so rounding of the segments can only
// cost time, never a hit inside an entered cell.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/intersection/triangle_leaves.hpp>
#include <glint/trees/bih_builder.hpp>
#include <glint/trees/kdtree_builder.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// A tree built by B over triangles of intersector P, encoded with layout L.
/// Leaves are TriangleLeaves<P> (kd-tree leaves may repeat triangles), tested through the
/// leaf callable intersect() takes; hits report the original triangle index in StoreHit::id.
/// Queries are const and keep their state on the caller's stack: any number of threads may
/// query one tree at once.
template <TreeBuilder B, TriangleIntersector P, NodeLayout L>
    requires std::same_as<typename B::scalar_type, typename P::scalar_type>
class TreeAccelerator {
public:
    using scalar_type = typename P::scalar_type;  ///< float or double, shared by B and P.
    using T = scalar_type;                        ///< Shorthand for scalar_type.
    using Node = typename B::node_type;           ///< Encoded node (KdNode or BihNode).
    using builder_type = B;                       ///< The TreeBuilder policy.
    using intersector_type = P;                   ///< The TriangleIntersector policy.
    using layout_type = L;                        ///< The NodeLayout policy.
    static constexpr int max_stack = 64;          ///< Traversal stack entries (builders cap depth at 56).

    /// Builds with `builder` over `tris` and encodes the tree. Throws Error when the tree
    /// needs more than 2^29 nodes or leaf groups, or when B's options are invalid.
    explicit TreeAccelerator(std::span<const TriangleVertices<T>> tris, const B& builder = B{})
        : TreeAccelerator(tris, builder.build(tris)) {}

    /// From a tree B built over the same triangles (to encode one build in several layouts
    /// or for several intersectors).
    TreeAccelerator(std::span<const TriangleVertices<T>> tris, const BuiltTree<T>& tree) {
        if (tree.kind != B::kind || tree.triangle_count != tris.size())
            throw Error("TreeAccelerator: the built tree is not of this builder's kind over these " +
                        std::to_string(tris.size()) + " triangles");
        bounds_ = tree.bounds;
        std::vector<std::array<std::uint32_t, 2>> groups(tree.nodes.size(), {0u, 0u});
        std::vector<TriangleVertices<T>> leaf_tris;
        for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
            const BuildNode<T>& n = tree.nodes[i];
            if (!n.leaf || n.prim_count == 0) continue;
            const std::span<const std::uint32_t> ids(tree.prims.data() + n.prim_begin, n.prim_count);
            leaf_tris.clear();
            for (std::uint32_t id : ids) leaf_tris.push_back(tris[id]);
            const auto ref = leaves_.add(leaf_tris, ids);
            groups[i] = {ref.first, ref.second};
            detail::check_index(std::size_t(ref.first) + ref.second);
        }
        stats_ = L::encode(tree, std::span<const std::array<std::uint32_t, 2>>(groups), nodes_);
    }

    /// Closest hit with t in (ray.tmin, min(ray.tmax, hit.t)); true when `hit` was updated.
    bool closest_hit(const Ray<T>& ray, StoreHit<T>& hit) const {
        Ray<T> r = ray_before(ray, hit);  // local copies: the compiler keeps them in registers
        StoreHit<T> h = hit;
        const auto world = leaves_.prepare(r);
        LeafQuery<P, false> leaf(leaves_, r, world, h);
        if (!intersect<false>(r, leaf)) return false;
        hit = leaf.hit();
        return true;
    }
    /// Whether any triangle is hit with t in (ray.tmin, ray.tmax) (shadow rays).
    bool any_hit(const Ray<T>& ray) const {
        Ray<T> r = ray;
        StoreHit<T> h;
        const auto world = leaves_.prepare(r);
        LeafQuery<P, true> leaf(leaves_, r, world, h);
        return intersect<true>(r, leaf);
    }

    const LayoutStats& stats() const { return stats_; }  ///< Node accounting of the encoding.
    const TriangleLeaves<P>& leaves() const { return leaves_; }  ///< Triangle records of all leaves.
    const std::vector<Node>& nodes() const { return nodes_; }  ///< Encoded nodes; nodes()[0] is the root.
    const AABB<T>& bounds() const { return bounds_; }  ///< Box of the hittable triangles (world space).
    /// Node bytes plus triangle-record bytes.
    std::size_t total_bytes() const { return stats_.node_bytes() + leaves_.bytes(); }

    /// Closest (Any = false) or any hit through a leaf callable (LeafTest, e.g. a LeafQuery):
    /// `leaf(first, count)` is called for the non-empty leaves the ray enters, near to far,
    /// with the leaf's reference in the TriangleLeaves (leaves()); for closest hit it lowers
    /// ray.tmax to each hit it finds, and cells beyond ray.tmax are skipped.
    template <bool Any, LeafTest Leaf>
    [[gnu::always_inline]] bool intersect(Ray<T>& ray, Leaf&& leaf) const {
        // Plain arrays: glm's operator[] with a run-time index is a switch, i.e. a branch on
        // the split axis that incoherent rays mispredict.
        const T org[3] = {ray.origin.x, ray.origin.y, ray.origin.z};
        const T inv[3] = {T(1) / ray.direction.x, T(1) / ray.direction.y, T(1) / ray.direction.z};
        const std::uint32_t neg[3] = {std::signbit(ray.direction.x) ? 1u : 0u,
                                      std::signbit(ray.direction.y) ? 1u : 0u,
                                      std::signbit(ray.direction.z) ? 1u : 0u};
        T t0 = ray.tmin, t1 = ray.tmax;
        if (!clip(org, inv, neg, t0, t1)) return false;
        const Node* nodes = nodes_.data();
        Entry stack[max_stack];
        int sp = 0;
        std::uint32_t index = 0, base = 0;
        bool found = false;
        for (;;) {
            const Node* n = nodes + index;
            while (!n->is_leaf()) {
                if (n->is_pointer()) {
                    index = n->target();
                    base = L::block_base(index);
                    n = nodes + index;
                    continue;
                }
                if (!step(*n, org, inv, neg, index, base, t0, t1, stack, sp)) goto pop;
                n = nodes + index;
            }
            if (const std::uint32_t count = n->group_count()) {
                if (leaf(n->group_begin(), count)) {
                    if constexpr (Any) return true;
                    found = true;
                }
            }
        pop:
            for (;;) {
                if (sp == 0) return found;
                const Entry& e = stack[--sp];
                if constexpr (!Any) {
                    if (e.t0 > ray.tmax) continue;
                }
                index = e.index;
                base = e.base;
                t0 = e.t0;
                t1 = e.t1;
                if constexpr (!Any) t1 = ray.tmax < t1 ? ray.tmax : t1;
                break;
            }
        }
    }

private:
    struct Entry {
        std::uint32_t index, base;
        T t0, t1;
    };

    /// Clips (t0, t1) = (ray.tmin, ray.tmax) to the scene box; false when nothing is left.
    /// Entry and exit planes are chosen by the sign of the direction, not by comparing the
    /// two distances, so that a ray parallel to a face and lying in it ((face - o) * inf =
    /// NaN) keeps its interval: such a ray can hit triangles in that face. (AABB::intersect
    /// swaps by comparison and rejects it.) A NaN tmax stays NaN: such a ray hits nothing.
    [[gnu::always_inline]] bool clip(const T (&org)[3], const T (&inv)[3], const std::uint32_t (&neg)[3], T& t0,
                                     T& t1) const {
        for (int a = 0; a < 3; ++a) {
            const T tl = (bounds_.lo[a] - org[a]) * inv[a], th = (bounds_.hi[a] - org[a]) * inv[a];
            const T tn = neg[a] ? th : tl, tf = neg[a] ? tl : th;
            t0 = tn > t0 ? tn : t0;
            t1 = tf < t1 ? tf : t1;
        }
        return t0 <= t1;
    }

    /// One step at split node `n` (cell `index`, segment (t0, t1)): moves to the child the
    /// ray enters first and pushes the other when both are entered; false when neither is
    /// (the caller pops).
    [[gnu::always_inline]] bool step(const Node& n, const T (&org)[3], const T (&inv)[3],
                                     const std::uint32_t (&neg)[3], std::uint32_t& index, std::uint32_t base, T& t0,
                                     T& t1, Entry* stack, int& sp) const {
        const Node* nodes = nodes_.data();
        const int axis = n.axis();
        const std::uint32_t first = L::first_child(n, index, base);
        const std::uint32_t ng = neg[axis];
        T tn, tf;
        n.distances(org[axis], inv[axis], ng, tn, tf);
        const std::uint32_t near = first + ng, far = first + 1 - ng;
        // Empty leaves (the empty space the SAH cut off) are never entered.
        const bool visit_near = !(tn < t0) & !nodes[near].is_empty_leaf();
        const bool visit_far = !(tf > t1) & !nodes[far].is_empty_leaf();
        if (!(visit_near | visit_far)) return false;
        // The far cell is always written to the stack but kept only when both cells are
        // entered; the cell entered is the near one if its segment is not empty, else the
        // far one.
        const T near_t1 = tn < t1 ? tn : t1, far_t0 = tf > t0 ? tf : t0;
        stack[sp] = Entry{far, base, far_t0, t1};
        sp += int(visit_near & visit_far);
        index = visit_near ? near : far;
        t1 = visit_near ? near_t1 : t1;
        t0 = visit_near ? t0 : far_t0;
        return true;
    }

    std::vector<Node> nodes_;
    TriangleLeaves<P> leaves_;
    AABB<T> bounds_;
    LayoutStats stats_;
};

/// SAH kd-tree over intersector P in layout L, e.g. KdTree<float, Ivm<float>, CompactSubtrees<31>>.
template <Scalar T, TriangleIntersector P, NodeLayout L>
using KdTree = TreeAccelerator<KdTreeBuilder<T>, P, L>;

/// Bounding interval hierarchy over intersector P in layout L.
template <Scalar T, TriangleIntersector P, NodeLayout L>
using Bih = TreeAccelerator<BihBuilder<T>, P, L>;

}  // namespace glint
