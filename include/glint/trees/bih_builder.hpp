// glint/trees/bih_builder.hpp: bounding interval hierarchy builder, after Waechter and
// Keller, "Instant ray tracing: the bounding interval hierarchy" (EGSR 2006).
//
// Szécsi 2009, §4.2: the BIH is a kd-tree-like binary tree whose node stores
// two planes on one axis, the maximum of the left child's triangles and the minimum of the
// right child's, so each triangle is referenced exactly once and the two children may
// overlap or leave empty space between them.
//
// Construction is Waechter and Keller's "global heuristic": the split plane is the middle of
// the longest axis of the node's *candidate cell* (a box that starts as the scene box and is
// halved at every level, independent of the triangles' bounds), triangles are partitioned
// in place by the centre of their bounding box, and the two clip planes are taken from the
// triangles on each side. When all triangles fall on one side, the candidate cell is halved
// towards them and the split tried again (no node is made). A node becomes a leaf with at
// most `leaf_size` triangles, at depth `max_depth` (bounded by the traversal stack), or when
// 64 halvings could not separate the triangles (they share one centre). Build is
// O(N log N) (one linear partition per level, in place). Triangles that can never be hit
// (a non-finite vertex, or exactly zero area) are left out (detail::can_be_hit, tree.hpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// Limits of the BIH build (BihBuilder::options); the split rule itself has no parameters.
struct BihBuildOptions {
    /// At most this many triangles make a leaf. Leaves are tested 8 triangles at a time (SIMD
    /// batches), so leaves larger than Waechter and Keller's 4 pay (docs/history/trees.md).
    std::uint32_t leaf_size = 16;
    int max_depth = 56;           ///< Deepest split level; capped at 56 (the traversal stack holds 64 entries).
};

namespace detail {

template <class T>
class BihBuild {
public:
    BihBuild(std::span<const TriangleVertices<T>> tris, const BihBuildOptions& opt) : tris_(tris), opt_(opt) {}

    BuiltTree<T> run() {
        out_.kind = TreeKind::bih;
        out_.triangle_count = tris_.size();
        boxes_.resize(tris_.size());
        for (std::uint32_t i = 0; i < tris_.size(); ++i) {
            const auto& t = tris_[i];
            if (!detail::can_be_hit(t)) continue;
            AABB<T> b;
            for (const auto& p : t) b.extend(p);
            boxes_[i] = b;
            out_.bounds.extend(b);
            out_.prims.push_back(i);
        }
        out_.nodes.reserve(out_.prims.size() + 1);
        build(0, static_cast<std::uint32_t>(out_.prims.size()), out_.bounds, 0);
        return std::move(out_);
    }

private:
    std::uint32_t make_leaf(std::uint32_t begin, std::uint32_t end) {
        const auto index = static_cast<std::uint32_t>(out_.nodes.size());
        BuildNode<T> nd;
        nd.leaf = true;
        nd.prim_begin = begin;
        nd.prim_count = end - begin;
        out_.nodes.push_back(nd);
        return index;
    }

    std::uint32_t build(std::uint32_t begin, std::uint32_t end, AABB<T> cell, int depth) {
        const int max_depth = std::min(opt_.max_depth, 56);
        if (end - begin <= opt_.leaf_size || depth >= max_depth) return make_leaf(begin, end);
        auto* prims = out_.prims.data();
        for (int attempt = 0; attempt < 64; ++attempt) {
            const int k = cell.longest_axis();
            const T mid = (cell.lo[k] + cell.hi[k]) * T(0.5);
            if (!(mid > cell.lo[k] && mid < cell.hi[k])) break;  // cell too small to halve
            // Partition by bounding-box centre (twice the centre, to avoid a rounding step).
            const T mid2 = mid + mid;
            auto is_left = [&](std::uint32_t i) { return boxes_[i].lo[k] + boxes_[i].hi[k] < mid2; };
            std::uint32_t* split = std::partition(prims + begin, prims + end, is_left);
            const auto m = static_cast<std::uint32_t>(split - prims);
            if (m == begin) {  // all right: continue in the right half of the cell
                cell.lo[k] = mid;
                continue;
            }
            if (m == end) {
                cell.hi[k] = mid;
                continue;
            }
            T lmax = -infinity<T>, rmin = infinity<T>;
            for (std::uint32_t i = begin; i < m; ++i) lmax = std::max(lmax, boxes_[prims[i]].hi[k]);
            for (std::uint32_t i = m; i < end; ++i) rmin = std::min(rmin, boxes_[prims[i]].lo[k]);
            const auto index = static_cast<std::uint32_t>(out_.nodes.size());
            out_.nodes.emplace_back();
            AABB<T> lcell = cell, rcell = cell;
            lcell.hi[k] = mid;
            rcell.lo[k] = mid;
            const std::uint32_t l = build(begin, m, lcell, depth + 1);
            const std::uint32_t r = build(m, end, rcell, depth + 1);
            BuildNode<T>& nd = out_.nodes[index];
            nd.leaf = false;
            nd.axis = static_cast<std::uint8_t>(k);
            nd.plane[0] = lmax;
            nd.plane[1] = rmin;
            nd.left = l;
            nd.right = r;
            return index;
        }
        return make_leaf(begin, end);
    }

    std::span<const TriangleVertices<T>> tris_;
    BihBuildOptions opt_;
    std::vector<AABB<T>> boxes_;
    BuiltTree<T> out_;
};

}  // namespace detail

/// BIH builder policy (TreeBuilder).
template <Scalar T>
struct BihBuilder {
    using scalar_type = T;         ///< Precision of the input vertices and planes.
    using node_type = BihNode<T>;  ///< Traversed in these nodes (tree.hpp).
    static constexpr TreeKind kind = TreeKind::bih;  ///< Makes BIH trees (two planes per node).
    BihBuildOptions options{};     ///< Leaf size and depth limit.

    /// Builds the BIH over `tris` (unhittable triangles left out); O(N log N); throws
    /// nothing but std::bad_alloc.
    BuiltTree<T> build(std::span<const TriangleVertices<T>> tris) const {
        return detail::BihBuild<T>(tris, options).run();
    }
};

}  // namespace glint
