// glint/trees/binary_bvh.hpp: the binary BVH the binned SAH builder (bvh_builder.hpp) makes
// and the wide collapse (wide_collapse.hpp) reads: its build options, its node slots, and
// the clippers that chop primitives for spatial splits (clip_triangle for triangles).
//
// The builder's tree has node slots assigned from the reference ranges, not
// from the order of work: a node over n references at slot s has its left child at s + 1
// and its right child at s + 2 n_L (a subtree over n references needs at most 2n - 1 slots;
// with spatial splits n counts the room a subtree has for references, see BinnedSah).
// So subtrees built by different threads never share an allocator, and the tree (every
// slot, every primitive order) is the same for any thread count. The wide collapse
// (wide_collapse.hpp) reads it from the root.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/parallel.hpp>
#include <glint/core/math.hpp>

namespace glint {

/// Where the wide collapse (wide_collapse.hpp) puts a node's children in the node array: each
/// child's subtree right after it (depth first), or a node's inner children side by side in
/// one block, then their subtrees (Szécsi 2009, §4.4's idea of placing a node's children together).
enum class WideNodeOrder { depth_first, sibling_blocks };

/// Cost constants and limits of the binned SAH build (docs/trees.md: how they were chosen).
struct BvhBuildOptions {
    float traversal_cost = 1.0f;     ///< C_T, per binary node; finite, >= 0.
    float intersection_cost = 1.0f;  ///< C_I, per started leaf block; finite, > 0.
    std::uint32_t leaf_block = 8;    ///< Primitives tested together (the batch kernel's width); >= 1.
    std::uint32_t max_leaf = 16;     ///< At most this many primitives per leaf (1 ... 16).
    std::uint32_t bins = 16;         ///< Centre bins per axis (2 ... 64).
    unsigned threads = 1;            ///< Build threads; 0: std::thread::hardware_concurrency().
    /// A host's executor (core/parallel.hpp) for the build's parallel part: a large node's two
    /// children run as executor(2, task) instead of one on a std::thread of glint's, and
    /// `threads` is not read. Tasks call the executor again (the recursion), so it must allow
    /// nested calls (TBB's parallel_for and work-stealing pools do; a fixed pool whose worker
    /// blocks on a task queued behind it deadlocks). The tree does not depend on it.
    Executor executor{};
    WideNodeOrder node_order = WideNodeOrder::depth_first;  ///< The wide nodes' order in memory.
    float wide_node_cost = 1.0f;     ///< C_N, per wide node, in the wide collapse (wide_collapse.hpp); finite, >= 0.
    /// Spatial splits (Stich, Friedrich, Dietrich 2009; see detail::BinnedSah): tried at a node
    /// where the best object split's two boxes overlap by more than spatial_alpha times the
    /// root's surface area (and the node's own limits below); references stay at most
    /// spatial_budget times the primitives. The defaults are top_spatial_splits(), the cheap
    /// choice (docs/trees.md); full_spatial_splits() tries them at every node; false: object
    /// splits alone (the binned SAH tree).
    bool spatial_splits = true;
    float spatial_alpha = 1e-5f;     ///< Overlap, as a fraction of the root's area, that tries a spatial split (0 ... 1).
    float spatial_budget = 1.1f;     ///< Cap on references per primitive over the tree (1 ... 4; full splits: 1.5).
    /// Overlap, as a fraction of the node's own area, that a spatial split also needs (0 ... 1;
    /// 0: alpha alone decides, as full splits do).
    float spatial_node_overlap = 0.4f;
    /// Spatial splits only at nodes of at least 1/2^k of the root's references (the top k
    /// levels of a balanced tree); 0: at every node (full splits).
    std::uint32_t spatial_levels = 4;
    /// Spatial search by boxes: a reference counted in its first and last bin whole, the
    /// sides cut at the plane, no clipping (the split itself still clips exactly).
    bool spatial_box_chop = true;
    bool spatial_one_axis = true;    ///< Spatial search on the node's longest axis only.

    /// Spatial splits at every node, searched exactly on all three axes, budget 1.5 (Stich
    /// et al. 2009): the best trees, at about 15 times the binned build's time.
    static BvhBuildOptions full_spatial_splits() {
        BvhBuildOptions o;
        o.spatial_splits = true;
        o.spatial_budget = 1.5f;
        o.spatial_node_overlap = 0.0f;
        o.spatial_levels = 0;
        o.spatial_box_chop = o.spatial_one_axis = false;
        return o;
    }
    /// Spatial splits where they pay most, at about the binned build's cost (docs/trees.md,
    /// "Spatial splits in the top levels"), the defaults: the top 4 levels, nodes whose object
    /// split overlaps by more than 0.4 of the node's area, longest axis, box chop, budget 1.1.
    static BvhBuildOptions top_spatial_splits() { return {}; }

    /// Throws Error naming the first option outside its range (build_binary_bvh calls it).
    void check() const {
        auto bad = [](const std::string& what) { throw Error("BvhBuildOptions: " + what); };
        if (!(traversal_cost >= 0) || !(intersection_cost > 0) || !(wide_node_cost >= 0) ||
            !std::isfinite(traversal_cost) || !std::isfinite(intersection_cost) || !std::isfinite(wide_node_cost))
            bad("costs must be finite, traversal_cost >= 0, intersection_cost > 0 and wide_node_cost >= 0 (got " +
                std::to_string(traversal_cost) + ", " + std::to_string(intersection_cost) + ", " +
                std::to_string(wide_node_cost) + ")");
        if (leaf_block < 1 || max_leaf < 1 || max_leaf > 16)
            bad("leaf_block >= 1 and max_leaf in 1 ... 16 (got " + std::to_string(leaf_block) + ", " +
                std::to_string(max_leaf) + ")");
        if (bins < 2 || bins > 64) bad("bins in 2 ... 64 (got " + std::to_string(bins) + ")");
        if (!(spatial_alpha >= 0 && spatial_alpha <= 1) || !(spatial_budget >= 1 && spatial_budget <= 4))
            bad("spatial_alpha in 0 ... 1 and spatial_budget in 1 ... 4 (got " + std::to_string(spatial_alpha) + ", " +
                std::to_string(spatial_budget) + ")");
        if (!(spatial_node_overlap >= 0 && spatial_node_overlap <= 1))
            bad("spatial_node_overlap in 0 ... 1 (got " + std::to_string(spatial_node_overlap) + ")");
    }
    /// Leaf blocks started by n primitives: the unit in which the SAH counts C_I.
    std::uint32_t blocks(std::uint32_t n) const { return (n + leaf_block - 1) / leaf_block; }
    /// Threads the build uses: `threads`, or the hardware's count (at least 1) when it is 0.
    unsigned thread_count() const {
        return threads ? threads : std::max(1u, std::thread::hardware_concurrency());
    }
};

/// One slot of the binary tree. A leaf has right == 0 (slot 0 is the root, never a child).
struct BinaryBvhNode {
    AABB<float> box;                     ///< Bounds of the node's references, world space.
    /// First index into BinaryBvh::prims of the node's range.
    std::uint32_t begin = 0, count = 0;  ///< Primitives in the range (a leaf's contents, an inner node's span).
    std::uint32_t right = 0;             ///< Inner: the right child's slot; the left one is this slot + 1.
    bool leaf() const { return right == 0; }  ///< Leaf (right == 0), also true for unused slots.
};

/// The binned SAH tree: `nodes` has 2n - 1 slots for n primitives (unused slots stay
/// default); `prims` is the primitive order, leaf ranges index it.
struct BinaryBvh {
    std::vector<BinaryBvhNode> nodes;  ///< Slots; nodes[0] is the root, empty when no primitive was kept.
    std::vector<std::uint32_t> prims;  ///< Primitive indices in leaf order (repeated with spatial splits).
    bool empty() const { return prims.empty(); }  ///< No primitive could be hit (no tree).
};

/// What spatial splits need from a primitive: clip(p, axis, region) is a box holding every
/// point of primitive p that lies in `region`'s slab on `axis`, within `region` (empty when
/// there is none). `region` is a box already holding p's part in the node.
template <class C>
concept PrimitiveClipper = requires(const C& clip, std::uint32_t p, int axis, const AABB<float>& region) {
    { clip(p, axis, region) } -> std::convertible_to<AABB<float>>;
};

/// No clipping: a primitive known only by its box. Its part in `region` is bounded by
/// `region` itself, so spatial splits chop boxes (each piece the box's part in the slab).
struct NoClipper {
    /// Returns `region`: the piece of any box inside the slab is bounded by it.
    AABB<float> operator()(std::uint32_t, int, const AABB<float>& region) const { return region; }
};

namespace detail {
/// The next float after finite x toward +infinity (dir = 1) or -infinity (dir = -1).
inline float float_step(float x, int dir) {
    if (x == 0.0f) return dir > 0 ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
    const auto bits = std::bit_cast<std::uint32_t>(x);
    return std::bit_cast<float>((x > 0) == (dir > 0) ? bits + 1 : bits - 1);
}
}  // namespace detail

/// The box of the part of triangle (a, b, c) between the planes of `region` on `axis`, within
/// `region`, never smaller than that part (Stich et al. 2009 §3: a chopped reference is
/// bounded by the triangle's part, not by its box's). That part's corners lie on the edges:
/// each edge's piece between the two planes is found in double precision, the box of the
/// pieces' ends rounded two floats outward (one for the rounding to float; the double's own
/// error is far below the other), then intersected with `region` (whose planes are exact).
inline AABB<float> clip_triangle(const Vec3f& a, const Vec3f& b, const Vec3f& c, int axis, const AABB<float>& region) {
    const Vec3d v[3] = {Vec3d(a), Vec3d(b), Vec3d(c)};
    const double w0 = region.lo[axis], w1 = region.hi[axis];
    Vec3d lo(infinity<double>), hi(-infinity<double>);
    for (int i = 0; i < 3; ++i) {
        Vec3d p = v[i], q = v[i == 2 ? 0 : i + 1];
        if (p[axis] > q[axis]) std::swap(p, q);
        if (q[axis] < w0 || p[axis] > w1) continue;  // the edge misses the slab
        const Vec3d d = q - p;
        const double inv = d[axis] > 0 ? 1.0 / d[axis] : 0.0;
        const Vec3d e0 = p + d * std::max(0.0, (w0 - p[axis]) * inv);
        const Vec3d e1 = d[axis] > 0 ? p + d * std::min(1.0, (w1 - p[axis]) * inv) : q;
        lo = glm::min(lo, glm::min(e0, e1));
        hi = glm::max(hi, glm::max(e0, e1));
    }
    AABB<float> out;
    if (!(lo[axis] <= hi[axis])) return out;  // no point of the triangle between the planes
    for (int ax = 0; ax < 3; ++ax) {  // two ulps out: one for rounding to float, one for the double's error
        out.lo[ax] = std::max(region.lo[ax], detail::float_step(detail::float_step(float(lo[ax]), -1), -1));
        out.hi[ax] = std::min(region.hi[ax], detail::float_step(detail::float_step(float(hi[ax]), 1), 1));
    }
    return out;
}

}  // namespace glint
