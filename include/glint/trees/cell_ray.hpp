// glint/trees/cell_ray.hpp: what the uniform grid (uniform_grid.hpp) and the octree
// (octree.hpp) share: the ray in arrays (origin, inverse direction, sign), its clip to a box,
// the margin by which primitives are binned into cells, and the default cell hook.
//
// Both structures bin a primitive into every cell its box (and the caller's exact overlap
// test) meets, the cell's box grown by a small margin, and traverse cells front to back,
// stopping when the closest hit found lies inside the current cell (the in-cell check). The
// margin makes both robust to rounding: a hit point within rounding of a cell boundary, or
// of a corner the traversal steps around, lies in the grown box of every cell it touches, so
// its primitive is tested in whichever of them the traversal visits, and a hit found up to
// the computed exit of a cell is never beaten by a primitive of a later cell.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>

#include <glint/core/aabb.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>

namespace glint {

/// What the grid's and the octree's intersect() call at every cell or node they visit
/// (`hook()`): a counter for measurements, or NoCellHook.
template <class H>
concept CellHook = std::invocable<H&>;

/// The default cell hook: nothing (traversal compiles as without a hook).
struct NoCellHook {
    void operator()() const noexcept {}  ///< Does nothing.
};

namespace detail {

/// A ray as the cell traversals read it: plain arrays (glm's run-time operator[] is a switch).
template <class T>
struct CellRay {
    T org[3], dir[3], inv[3];  // inv: 1 / dir (+-inf for a zero component, signed like it)
    bool neg[3];               // sign bit of dir

    explicit CellRay(const Ray<T>& r) {
        for (int a = 0; a < 3; ++a) {
            org[a] = r.origin[a];
            dir[a] = r.direction[a];
            inv[a] = T(1) / dir[a];
            neg[a] = std::signbit(dir[a]);
        }
    }
    /// A ray with a NaN or infinite component, or a zero direction, hits nothing.
    bool valid() const {
        bool finite = true;
        for (int a = 0; a < 3; ++a) finite = finite && std::isfinite(org[a]) && std::isfinite(dir[a]);
        return finite && (dir[0] != 0 || dir[1] != 0 || dir[2] != 0);
    }
    /// (t0, t1) = ray's (tmin, tmax) clipped to `box` (AABB::intersect: entry and exit planes
    /// by the direction's sign, so a ray lying in a face keeps its interval); false when
    /// nothing is left.
    bool clip(const AABB<T>& box, const Ray<T>& ray, T& t0, T& t1) const {
        return box.intersect(ray, Vec3<T>(inv[0], inv[1], inv[2]), t0, t1);
    }
};

/// The margin by which a cell's box is grown on each axis before binning: 1e-4 of the cell's
/// size there plus 1e-6 of the coordinates' magnitude (far beyond float rounding of either).
template <class T>
Vec3<T> cell_margin(const AABB<T>& cell, const AABB<T>& bounds) {
    Vec3<T> m;
    for (int a = 0; a < 3; ++a)
        m[a] = T(1e-4) * (cell.hi[a] - cell.lo[a]) +
               T(1e-6) * std::max({std::abs(bounds.lo[a]), std::abs(bounds.hi[a]), bounds.hi[a] - bounds.lo[a]});
    return m;
}

/// `box` grown by `m` on every side.
template <class T>
AABB<T> grown(const AABB<T>& box, const Vec3<T>& m) {
    return AABB<T>{box.lo - m, box.hi + m};
}

/// Whether closed boxes a and b share a point.
template <class T>
bool boxes_meet(const AABB<T>& a, const AABB<T>& b) {
    return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y && a.lo.z <= b.hi.z &&
           b.lo.z <= a.hi.z;
}

/// Whether a primitive's box can be binned at all: not empty and finite.
template <class T>
bool binnable(const AABB<T>& b) {
    return !b.empty() && all_finite(b.lo) && all_finite(b.hi);
}

}  // namespace detail

/// The overlap test of a grid or octree build when the caller gives none: the primitive's
/// box meets the (grown) cell box, which the build has checked already, so always true.
struct BoxOverlap {
    /// True: the box test the build made is all this test asks.
    template <class T>
    bool operator()(std::uint32_t, const AABB<T>&) const noexcept {
        return true;
    }
};

}  // namespace glint
