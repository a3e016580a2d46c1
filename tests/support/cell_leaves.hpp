// tests/support/cell_leaves.hpp: a triangle mesh as the uniform grid and the octree
// (trees/uniform_grid.hpp, trees/octree.hpp) see it, for their tests and bench_grids (a
// fixture, not part of the library): the triangles' boxes to build over, an exact
// triangle-box overlap test, and the closest-hit and any-hit queries through a leaf callable
// that tests each referenced triangle with its Möller-Trumbore record (one scalar test a
// triangle, MollerTrumbore<float>'s own test). Ties in t go to the lower triangle index, as
// BruteForce<MollerTrumbore<float>> breaks them, so the hits can be compared exactly.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/triangle_leaves.hpp>
#include <glint/trees/cell_ray.hpp>
#include <glint/trees/kdtree_builder.hpp>  // detail::clipped_bounds
#include <glint/trees/tree.hpp>

namespace glint {

/// A per-test counter that counts nothing.
struct NoTestCount {
    void operator()() const noexcept {}
};

/// Möller-Trumbore records and boxes of a triangle soup, by triangle index.
class TriangleCells {
public:
    using MT = MollerTrumbore<float>;

    /// Records and boxes of `tris` (kept by reference for overlaps(): it must outlive this);
    /// a triangle no ray can hit (detail::can_be_hit) gets an empty box and is never binned.
    explicit TriangleCells(std::span<const TriangleVertices<float>> tris) : tris_(tris) {
        records_.reserve(tris.size());
        boxes_.resize(tris.size());
        for (std::size_t i = 0; i < tris.size(); ++i) {
            const auto& t = tris[i];
            records_.push_back(MT::build(Vec3d(t[0]), Vec3d(t[1]), Vec3d(t[2])));
            if (detail::can_be_hit(t))
                for (const auto& p : t) boxes_[i].extend(p);
        }
    }

    std::span<const AABB<float>> boxes() const { return boxes_; }

    /// Whether triangle i meets the closed box `cell` (clipped to it in double precision).
    bool overlaps(std::uint32_t i, const AABB<float>& cell) const {
        const auto& t = tris_[i];
        AABB<double> out;
        return detail::clipped_bounds(Vec3d(t[0]), Vec3d(t[1]), Vec3d(t[2]), AABB<double>{Vec3d(cell.lo), Vec3d(cell.hi)},
                                      out);
    }
    /// overlaps() as the builds take it.
    auto overlap_test() const {
        return [this](std::uint32_t i, const AABB<float>& cell) { return overlaps(i, cell); };
    }

    /// Closest hit with t in (ray.tmin, min(ray.tmax, hit.t)) through `acc.intersect`
    /// (a UniformGrid or an Octree built over boxes()); `count()` per triangle test.
    template <class Accel, class Count = NoTestCount, class Hook = NoCellHook>
    bool closest_hit(const Accel& acc, const Ray<float>& ray, StoreHit<float>& hit, Count&& count = Count{},
                     Hook&& hook = Hook{}) const {
        Ray<float> r = ray_before(ray, hit);
        MT::RayData rd = MT::prepare(r);
        StoreHit<float> best = hit;
        bool found = false;
        const std::uint32_t* prims = acc.prims().data();
        const auto leaf = [&](std::uint32_t first, std::uint32_t n) {
            bool any = false;
            for (std::uint32_t k = first; k < first + n; ++k) {
                const std::uint32_t id = prims[k];
                count();
                TriangleHit<float> h;
                if (!intersect_record(records_[id], rd, h)) continue;
                if (found && h.t == best.t && id > best.id) continue;  // a tie: the lower index wins
                static_cast<TriangleHit<float>&>(best) = h;
                best.id = id;
                found = any = true;
                r.tmax = h.t;
                rd.tmax = std::nextafter(h.t, std::numeric_limits<float>::infinity());  // ties still pass
            }
            return any;
        };
        acc.template intersect<false>(r, leaf, hook);
        if (found) hit = best;
        return found;
    }

    /// Whether any triangle is hit with t in (ray.tmin, ray.tmax), through `acc.intersect`.
    template <class Accel, class Count = NoTestCount, class Hook = NoCellHook>
    bool any_hit(const Accel& acc, const Ray<float>& ray, Count&& count = Count{}, Hook&& hook = Hook{}) const {
        Ray<float> r = ray;
        const MT::RayData rd = MT::prepare(r);
        const std::uint32_t* prims = acc.prims().data();
        const auto leaf = [&](std::uint32_t first, std::uint32_t n) {
            for (std::uint32_t k = first; k < first + n; ++k) {
                count();
                TriangleHit<float> h;
                if (intersect_record(records_[prims[k]], rd, h)) return true;
            }
            return false;
        };
        return acc.template intersect<true>(r, leaf, hook);
    }

private:
    std::span<const TriangleVertices<float>> tris_;
    std::vector<MT> records_;
    std::vector<AABB<float>> boxes_;
};

}  // namespace glint
