// glint/trees/uniform_grid.hpp: a uniform grid over primitives known by their boxes,
// traversed by 3D-DDA (Amanatides and Woo 1987), with a leaf callable per cell.
//
// A baseline for Szécsi 2009, §4.2's claim that a kd-tree needs fewer intersection tests
// than a uniform grid or an octree (benchmarks/bench_grids.cpp measures it). The grid
// never knows what a primitive is: it is built from boxes (and, optionally, the caller's
// exact test of a primitive against a cell's box), and intersect() calls the caller's leaf
// callable `leaf(first, count)` for the cells the ray visits, near to far, with the cell's
// range of prims(), as the trees do (trees/wide_bvh.hpp; madmann91/bvh v2).
//
// Resolution: about `cells_per_primitive` cells per (binnable) primitive in total (default 4),
// cells as close to cubes as the scene's box allows: cell side s = cbrt(V / (4 N)) with V the
// box's volume (each side floored at 1e-3 of the longest, so flat scenes get a finite s),
// n_a = round(extent_a / s) cells on axis a, clamped to [1, max_resolution].
// Binning: a primitive goes into every cell whose box, grown by detail::cell_margin, meets the
// primitive's box and passes the caller's overlap test (cell_ray.hpp says why the margin).
// Traversal: the ray is clipped to the grid's box and walked cell by cell; the next cell is
// across the nearest of the three next cell planes, each computed from its plane's position
// (not accumulated). A closest-hit leaf callable lowers ray.tmax; the walk stops once
// ray.tmax lies inside the current cell (the in-cell check: a primitive hit before the cell's
// exit lies in a cell already visited, so nothing further can be nearer), or when the ray
// leaves the grid.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/buckets.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle_leaves.hpp>
#include <glint/trees/cell_ray.hpp>

namespace glint {

/// How a UniformGrid chooses its resolution (see the header comment).
struct UniformGridOptions {
    double cells_per_primitive = 4.0;   ///< Target total cells per binnable primitive; positive and finite.
    std::uint32_t max_resolution = 512;  ///< Most cells on one axis, in [1, 1024].
};

/// A uniform grid over primitive boxes; queries through a leaf callable (see the header comment).
/// Queries are const and keep their state on the caller's stack (thread-safe).
template <Scalar T>
class UniformGrid {
public:
    using scalar_type = T;  ///< Precision of the boxes and of the rays.

    UniformGrid() = default;  ///< An empty grid: every query misses.
    /// Bins `boxes` (primitive i's box is boxes[i]; empty or non-finite ones are left out) by
    /// box overlap alone.
    explicit UniformGrid(std::span<const AABB<T>> boxes, const UniformGridOptions& opt = {})
        : UniformGrid(boxes, opt, BoxOverlap{}) {}
    /// Bins `boxes`, keeping primitive i in a cell only where `overlaps(i, cell_box)` (the cell's
    /// box grown by the margin) is true, e.g. an exact triangle-box test. Throws glint::Error
    /// for options out of range or more than 2^32 - 1 references.
    template <class Overlap>
    UniformGrid(std::span<const AABB<T>> boxes, const UniformGridOptions& opt, Overlap&& overlaps) {
        check(opt);
        std::uint64_t n = 0;
        for (const AABB<T>& b : boxes)
            if (detail::binnable(b)) bounds_.extend(b), ++n;
        if (n == 0) return;
        choose_resolution(opt, n);
        bin(boxes, overlaps);
    }

    /// Closest (Any = false) or any hit through `leaf(first, count)`, called for the non-empty
    /// cells the ray visits, near to far, with the cell's range of prims(); a closest-hit
    /// callable lowers ray.tmax to each hit it finds. `hook()` is called at every cell visited,
    /// empty ones included. True when some call of `leaf` returned true.
    template <bool Any, LeafTest Leaf, CellHook Hook = NoCellHook>
    bool intersect(Ray<T>& ray, Leaf&& leaf, Hook&& hook = {}) const {
        const detail::CellRay<T> r(ray);
        T t0, t1;
        if (cell_begin_.empty() || !r.valid() || !r.clip(bounds_, ray, t0, t1)) return false;
        int idx[3], step[3];
        T next[3];
        for (int a = 0; a < 3; ++a) {
            const T p = r.org[a] + t0 * r.dir[a];
            idx[a] = std::clamp(int(std::floor((p - bounds_.lo[a]) * inv_size_[a])), 0, int(res_[a]) - 1);
            step[a] = r.dir[a] > 0 ? 1 : r.dir[a] < 0 ? -1 : 0;
            next[a] = next_plane(r, a, idx[a], step[a]);
        }
        bool found = false;
        for (;;) {
            hook();
            const std::size_t cell = (std::size_t(idx[2]) * res_[1] + std::size_t(idx[1])) * res_[0] + std::size_t(idx[0]);
            const std::uint32_t b = cell_begin_[cell], e = cell_begin_[cell + 1];
            if (e > b && leaf(b, e - b)) {
                if constexpr (Any) return true;
                found = true;
            }
            const int a = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
            const T exit = next[a] < t1 ? next[a] : t1;
            if (!(ray.tmax > exit) || !(exit < t1)) return found;  // in-cell check, or the ray ends here
            idx[a] += step[a];
            if (idx[a] < 0 || idx[a] >= int(res_[a])) return found;
            next[a] = next_plane(r, a, idx[a], step[a]);
        }
    }

    /// Primitive indices of all cells; cell c holds prims()[cell_begin()[c] ... cell_begin()[c+1] - 1].
    const std::vector<std::uint32_t>& prims() const { return prims_; }
    /// Per cell (x fastest, then y, then z), its first index into prims(); one more entry at the end.
    const std::vector<std::uint32_t>& cell_begin() const { return cell_begin_; }
    const AABB<T>& bounds() const { return bounds_; }  ///< Box of the binned primitives (empty: no cells).
    /// Cells on each axis (0 0 0 for an empty grid).
    std::array<std::uint32_t, 3> resolution() const { return {res_[0], res_[1], res_[2]}; }
    /// Number of cells.
    std::size_t cell_count() const { return cell_begin_.empty() ? 0 : cell_begin_.size() - 1; }
    /// Bytes of the cell table and the primitive references.
    std::size_t bytes() const { return (cell_begin_.size() + prims_.size()) * sizeof(std::uint32_t); }

private:
    static void check(const UniformGridOptions& opt) {
        if (!(opt.cells_per_primitive > 0) || !std::isfinite(opt.cells_per_primitive))
            throw Error("UniformGrid: cells_per_primitive must be positive and finite, got " +
                        std::to_string(opt.cells_per_primitive));
        if (opt.max_resolution < 1 || opt.max_resolution > 1024)
            throw Error("UniformGrid: max_resolution must lie in [1, 1024], got " + std::to_string(opt.max_resolution));
    }

    /// The t at which the ray leaves cell `i` on axis a through the plane ahead (+inf: parallel).
    T next_plane(const detail::CellRay<T>& r, int a, int i, int step) const {
        if (step == 0) return infinity<T>;
        const T plane = i + (step > 0) == int(res_[a]) ? bounds_.hi[a] : bounds_.lo[a] + T(i + (step > 0)) * size_[a];
        return (plane - r.org[a]) * r.inv[a];
    }

    void choose_resolution(const UniformGridOptions& opt, std::uint64_t n) {
        const Vec3<T> e = bounds_.extent();
        const double longest = std::max({double(e.x), double(e.y), double(e.z)});
        double volume = 1;
        for (int a = 0; a < 3; ++a) volume *= std::max(double(e[a]), 1e-3 * longest);
        const double side = std::cbrt(volume / (opt.cells_per_primitive * double(n)));
        for (int a = 0; a < 3; ++a) {
            const double cells = side > 0 ? std::round(double(e[a]) / side) : 1.0;
            res_[a] = std::uint32_t(std::clamp(cells, 1.0, double(opt.max_resolution)));
            size_[a] = e[a] / T(res_[a]);
            inv_size_[a] = e[a] > 0 ? T(res_[a]) / e[a] : T(0);
        }
    }

    /// Cell (i, j, k)'s box; the last cell on an axis ends at the grid's box.
    AABB<T> cell_box(const int (&c)[3]) const {
        AABB<T> b;
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = bounds_.lo[a] + T(c[a]) * size_[a];
            b.hi[a] = c[a] + 1 == int(res_[a]) ? bounds_.hi[a] : bounds_.lo[a] + T(c[a] + 1) * size_[a];
        }
        return b;
    }

    /// Cell index range [lo, hi] on axis a that coordinates [x0, x1] may touch.
    std::pair<int, int> cell_range(int a, T x0, T x1) const {
        const int last = int(res_[a]) - 1;
        const auto index = [&](T x) { return std::clamp(int(std::floor((x - bounds_.lo[a]) * inv_size_[a])), 0, last); };
        return {index(x0), index(x1)};
    }

    template <class Overlap>
    void bin(std::span<const AABB<T>> boxes, Overlap& overlaps) {
        const std::size_t cells = std::size_t(res_[0]) * res_[1] * res_[2];
        const Vec3<T> m = detail::cell_margin(cell_box({0, 0, 0}), bounds_);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> refs;  // (cell, primitive)
        for (std::uint32_t i = 0; i < boxes.size(); ++i) {
            if (!detail::binnable(boxes[i])) continue;
            std::pair<int, int> range[3];
            for (int a = 0; a < 3; ++a) range[a] = cell_range(a, boxes[i].lo[a] - m[a], boxes[i].hi[a] + m[a]);
            for (int z = range[2].first; z <= range[2].second; ++z)
                for (int y = range[1].first; y <= range[1].second; ++y)
                    for (int x = range[0].first; x <= range[0].second; ++x) {
                        const AABB<T> cell = detail::grown(cell_box({x, y, z}), m);
                        if (!detail::boxes_meet(cell, boxes[i]) || !overlaps(i, cell)) continue;
                        refs.emplace_back(std::uint32_t((std::size_t(z) * res_[1] + std::size_t(y)) * res_[0] + std::size_t(x)), i);
                        if (refs.size() >= std::size_t(UINT32_MAX))
                            throw Error("UniformGrid: more than 2^32 - 1 references");
                    }
        }
        fill_buckets(  // each cell in primitive order
            cells,
            [&](auto emit) {
                for (const auto& ref : refs) emit(ref.second, ref.first);
            },
            cell_begin_, prims_);
    }

    std::vector<std::uint32_t> cell_begin_, prims_;
    AABB<T> bounds_;
    std::uint32_t res_[3] = {0, 0, 0};  // a plain array: indexed by int axes
    Vec3<T> size_{0}, inv_size_{0};
};

}  // namespace glint
