// glint/lights/lie_octree.hpp: the octree whose leaf cells carry local illumination
// environments (Fernandez 2004, §3.1 and §4.3-4.4).
//
// The root is the cube around the scene's bounds (slightly enlarged, so that every surface
// point is inside). Nodes are created only where a sample lands: descend(x, depth) creates the
// path to the cell of the given depth that holds x (fixed-depth subdivision, §4.3: cells of
// one depth, no empty leaves where no sample went); split(node) replaces a leaf by its eight
// children (adaptive subdivision, §4.4). A leaf names its cell (the index of its LIE), or
// none while no sample has reached it. locate(x) is the read-only lookup rendering threads
// use: the cell holding x, or none where x is outside the cube or no sample reached.
// A point on a splitting plane belongs to the upper child, in every lookup.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>

namespace glint {

/// The octree of the local illumination environments: a cube around the scene, grown where
/// samples land. Construction (descend, split) is single-threaded; locate() is read-only.
template <Scalar T>
class LieOctree {
public:
    static constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();  ///< No node, no cell.

    /// A node: a leaf (with or without a cell) or an inner node with eight children.
    struct Node {
        std::uint32_t first_child = none;  ///< First of eight consecutive children, in octant order; none: a leaf.
        std::uint32_t cell = none;         ///< A leaf's LIE (index into Lie::cells()); none: no sample reached it.
        std::uint8_t depth = 0;            ///< Depth below the root (0); a cell's edge is 2 half_size() / 2^depth.
    };

    LieOctree() = default;
    /// The cube around `bounds`, enlarged by 1e-3 of its size on every side.
    explicit LieOctree(const AABB<T>& bounds) {
        if (bounds.empty() || !all_finite(bounds.lo) || !all_finite(bounds.hi))
            throw Error("LieOctree: the scene's bounds are empty or not finite");
        const Vec3<T> e = bounds.extent();
        half_ = std::max({e.x, e.y, e.z, T(1e-6)}) * T(0.5005);
        center_ = bounds.center();
        nodes_.push_back(Node{});
    }

    /// The leaf node holding x (creating the path down to `depth` where it is missing), or none
    /// where x is outside the cube. A leaf above `depth` that already has a cell is kept (an
    /// adaptive tree descends only where it has split).
    std::uint32_t descend(const Vec3<T>& x, int depth, bool create) {
        if (!inside(x)) return none;
        std::uint32_t n = 0;
        Vec3<T> c = center_;
        T h = half_;
        while (nodes_[n].depth < depth) {
            if (nodes_[n].first_child == none) {
                if (!create || nodes_[n].cell != none) break;
                split(n);
            }
            const int o = octant(x, c);
            h *= T(0.5);
            c += Vec3<T>(o & 1 ? h : -h, o & 2 ? h : -h, o & 4 ? h : -h);
            n = nodes_[n].first_child + std::uint32_t(o);
        }
        return n;
    }

    /// The cell holding x, or none (outside the cube, or a region no sample reached).
    std::uint32_t locate(const Vec3<T>& x) const {
        if (!inside(x)) return none;
        std::uint32_t n = 0;
        Vec3<T> c = center_;
        T h = half_;
        while (nodes_[n].first_child != none) {
            const int o = octant(x, c);
            h *= T(0.5);
            c += Vec3<T>(o & 1 ? h : -h, o & 2 ? h : -h, o & 4 ? h : -h);
            n = nodes_[n].first_child + std::uint32_t(o);
        }
        return nodes_[n].cell;
    }

    /// Makes leaf n an inner node with eight empty leaves; n's cell is dropped (returned).
    std::uint32_t split(std::uint32_t n) {
        if (nodes_[n].first_child != none) throw Error("LieOctree::split: node " + std::to_string(n) + " is not a leaf");
        const std::uint32_t dropped = nodes_[n].cell;
        const std::uint8_t d = std::uint8_t(nodes_[n].depth + 1);
        nodes_[n].first_child = std::uint32_t(nodes_.size());
        nodes_[n].cell = none;
        for (int i = 0; i < 8; ++i) nodes_.push_back(Node{none, none, d});
        return dropped;
    }

    /// Node n, writable for the builder (unchecked: n < nodes().size()); node 0 is the root.
    Node& node(std::uint32_t n) { return nodes_[n]; }
    /// Node n (unchecked: n < nodes().size()).
    const Node& node(std::uint32_t n) const { return nodes_[n]; }
    /// Every node, the root first; children are appended as nodes are split.
    const std::vector<Node>& nodes() const { return nodes_; }
    /// Centre of the root cube (world space).
    Vec3<T> center() const { return center_; }
    /// Half the root cube's edge (world units).
    T half_size() const { return half_; }

private:
    bool inside(const Vec3<T>& x) const {
        const Vec3<T> d = glm::abs(x - center_);
        return d.x <= half_ && d.y <= half_ && d.z <= half_;  // false for NaN
    }
    static int octant(const Vec3<T>& x, const Vec3<T>& c) {
        return (x.x >= c.x ? 1 : 0) | (x.y >= c.y ? 2 : 0) | (x.z >= c.z ? 4 : 0);
    }

    std::vector<Node> nodes_;
    Vec3<T> center_{0};
    T half_ = 0;
};

}  // namespace glint
