// glint/trees/octree.hpp: an octree over primitives known by their boxes, traversed front
// to back (an ordered recursion on an explicit stack, the child order from the ray's
// distances to the node's three mid planes, as in Revelles et al. 2000), with a leaf
// callable per leaf.
//
// A baseline for Szécsi 2009, §4.2's claim that a kd-tree needs fewer intersection tests
// than a uniform grid or an octree (benchmarks/bench_grids.cpp measures it). Like the uniform
// grid (uniform_grid.hpp) it never knows what a primitive is: it is built from boxes and an
// optional exact overlap test, and intersect() calls the caller's `leaf(first, count)` with a
// leaf's range of prims().
//
// Build: the root is the box of the binnable primitives; a node over more than `max_leaf`
// primitives, above depth `max_depth`, is split at its box's centre into eight children, and
// a primitive goes into every child whose box, grown by detail::cell_margin, meets its box
// and passes the caller's overlap test (cell_ray.hpp). An axis along which the node's extent
// is below 1e-3 of its longest (a flat scene's normal axis) is not split: its mid plane is
// stored as +inf, so every ray stays on the lower side, and the upper children stay empty.
// Traversal: the ray's interval in the node, (t0, t1), is cut at the mid planes it crosses
// (sorted by distance); the child where it starts comes from the side of each plane it is on
// just after t0, and each crossing flips one axis' bit. Non-empty children are pushed far to
// near; a closest-hit query returns once ray.tmax lies inside the current leaf (every cell
// still on the stack starts after it: the in-cell check) and skips cells that start beyond it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle_leaves.hpp>
#include <glint/trees/cell_ray.hpp>

namespace glint {

/// When an Octree stops splitting (see the header comment).
struct OctreeOptions {
    std::uint32_t max_leaf = 8;   ///< A node over at most this many primitives is a leaf; at least 1.
    std::uint32_t max_depth = 10;  ///< Nodes at this depth (the root's is 0) are leaves; at most 20.
};

/// An octree over primitive boxes; queries through a leaf callable (see the header comment).
/// Queries are const and keep their state on the caller's stack (thread-safe).
template <Scalar T>
class Octree {
public:
    using scalar_type = T;  ///< Precision of the boxes and of the rays.

    /// One node: an inner node's children are nodes first ... first + 7 (child c on the upper
    /// side of axis a where bit a of c is set); a leaf holds prims()[first ... first + count - 1].
    struct Node {
        T mid[3];                  ///< Inner nodes: the split planes (+inf: axis not split).
        std::uint32_t first = 0;   ///< Inner: the first child's index; leaf: the first prims() index.
        std::uint32_t count = 0;   ///< Leaf: primitives in it (0: empty); inner: Octree::inner.
    };
    static constexpr std::uint32_t inner = ~0u;  ///< Node::count of an inner node.

    Octree() = default;  ///< An empty octree: every query misses.
    /// Builds over `boxes` (primitive i's box is boxes[i]; empty or non-finite ones are left
    /// out) by box overlap alone.
    explicit Octree(std::span<const AABB<T>> boxes, const OctreeOptions& opt = {}) : Octree(boxes, opt, BoxOverlap{}) {}
    /// Builds over `boxes`, keeping primitive i in a node only where `overlaps(i, node_box)`
    /// (the node's box grown by the margin) is true, e.g. an exact triangle-box test. Throws
    /// glint::Error for options out of range or more than 2^32 - 2 references.
    template <class Overlap>
    Octree(std::span<const AABB<T>> boxes, const OctreeOptions& opt, Overlap&& overlaps) : opt_(opt) {
        if (opt.max_leaf < 1 || opt.max_depth > 20)
            throw Error("Octree: max_leaf must be at least 1 and max_depth at most 20, got " + std::to_string(opt.max_leaf) +
                        " and " + std::to_string(opt.max_depth));
        std::vector<std::uint32_t> ids;
        for (std::uint32_t i = 0; i < boxes.size(); ++i)
            if (detail::binnable(boxes[i])) bounds_.extend(boxes[i]), ids.push_back(i);
        if (ids.empty()) return;
        nodes_.emplace_back();
        build(0, bounds_, std::move(ids), 0, boxes, overlaps);
    }

    /// Closest (Any = false) or any hit through `leaf(first, count)`, called for the non-empty
    /// leaves the ray enters, near to far, with the leaf's range of prims(); a closest-hit
    /// callable lowers ray.tmax to each hit it finds. `hook()` is called at every node visited.
    /// True when some call of `leaf` returned true.
    template <bool Any, LeafTest Leaf, CellHook Hook = NoCellHook>
    bool intersect(Ray<T>& ray, Leaf&& leaf, Hook&& hook = {}) const {
        const detail::CellRay<T> r(ray);
        T t0, t1;
        if (nodes_.empty() || !r.valid() || !r.clip(bounds_, ray, t0, t1)) return false;
        Entry stack[max_stack];
        int sp = 0;
        stack[sp++] = {0, t0, t1};
        bool found = false;
        while (sp > 0) {
            const Entry e = stack[--sp];
            if (!(e.t0 <= ray.tmax)) continue;  // starts beyond the closest hit
            hook();
            const Node& n = nodes_[e.node];
            if (n.count != inner) {
                if (n.count > 0 && leaf(n.first, n.count)) {
                    if constexpr (Any) return true;
                    found = true;
                }
                if (!(ray.tmax > e.t1)) return found;  // in-cell check, or the ray ends in this leaf
                continue;
            }
            push_children(n, r, e, stack, sp);
        }
        return found;
    }

    const std::vector<Node>& nodes() const { return nodes_; }  ///< nodes()[0] is the root (none when empty).
    const std::vector<std::uint32_t>& prims() const { return prims_; }  ///< Primitive indices of all leaves.
    const AABB<T>& bounds() const { return bounds_; }  ///< The root's box (empty: no nodes).
    /// Bytes of the nodes and the primitive references.
    std::size_t bytes() const { return nodes_.size() * sizeof(Node) + prims_.size() * sizeof(std::uint32_t); }

private:
    struct Entry {
        std::uint32_t node;
        T t0, t1;
    };
    static constexpr int max_stack = 4 * 21;  // each level pops one entry and pushes at most four

    /// Pushes the non-empty children of inner node n that the ray's interval (e.t0, e.t1) enters, far first.
    void push_children(const Node& n, const detail::CellRay<T>& r, const Entry& e, Entry* stack, int& sp) const {
        T tm[3];
        unsigned bits = 0;
        int cross[3], k = 0;
        for (int a = 0; a < 3; ++a) {
            tm[a] = (n.mid[a] - r.org[a]) * r.inv[a];
            const bool upper = r.neg[a] ? tm[a] > e.t0 : tm[a] <= e.t0;  // the side just after t0 (NaN: lower)
            bits |= unsigned(upper) << a;
            if (tm[a] > e.t0 && tm[a] < e.t1) cross[k++] = a;
        }
        for (int i = 1; i < k; ++i)  // at most three: insertion sort by distance
            for (int j = i; j > 0 && tm[cross[j]] < tm[cross[j - 1]]; --j) std::swap(cross[j], cross[j - 1]);
        unsigned child[4];
        T from[4], to[4];
        child[0] = bits;
        from[0] = e.t0;
        for (int s = 0; s < k; ++s) {
            to[s] = from[s + 1] = tm[cross[s]];
            child[s + 1] = child[s] ^ (1u << cross[s]);
        }
        to[k] = e.t1;
        for (int s = k; s >= 0; --s) {
            const std::uint32_t c = n.first + child[s];
            if (nodes_[c].count != 0) stack[sp++] = {c, from[s], to[s]};
        }
    }

    template <class Overlap>
    void build(std::uint32_t index, const AABB<T>& box, std::vector<std::uint32_t> ids, std::uint32_t depth,
               std::span<const AABB<T>> boxes, Overlap& overlaps) {
        if (ids.size() <= opt_.max_leaf || depth >= opt_.max_depth) {
            if (prims_.size() + ids.size() >= std::size_t(inner)) throw Error("Octree: more than 2^32 - 2 references");
            nodes_[index].first = std::uint32_t(prims_.size());
            nodes_[index].count = std::uint32_t(ids.size());
            prims_.insert(prims_.end(), ids.begin(), ids.end());
            return;
        }
        const Vec3<T> e = box.extent();
        const T longest = std::max({e.x, e.y, e.z});
        Node n;
        for (int a = 0; a < 3; ++a) n.mid[a] = e[a] > T(1e-3) * longest ? box.center()[a] : infinity<T>;
        n.first = std::uint32_t(nodes_.size());
        n.count = inner;
        nodes_[index] = n;
        nodes_.resize(nodes_.size() + 8);
        std::vector<std::uint32_t> in;
        for (unsigned c = 0; c < 8; ++c) {
            AABB<T> cb = box;
            bool empty = false;
            for (int a = 0; a < 3; ++a) {
                const bool up = (c >> a) & 1u;
                if (std::isinf(n.mid[a])) empty = empty || up;  // an axis not split: the lower child spans it
                else (up ? cb.lo[a] : cb.hi[a]) = n.mid[a];
            }
            if (empty) continue;
            const AABB<T> grown = detail::grown(cb, detail::cell_margin(cb, bounds_));
            in.clear();
            for (std::uint32_t id : ids)
                if (detail::boxes_meet(grown, boxes[id]) && overlaps(id, grown)) in.push_back(id);
            build(n.first + c, cb, in, depth + 1, boxes, overlaps);
        }
    }

    std::vector<Node> nodes_;
    std::vector<std::uint32_t> prims_;
    AABB<T> bounds_;
    OctreeOptions opt_;
};

}  // namespace glint
