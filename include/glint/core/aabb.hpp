// glint/core/aabb.hpp: axis-aligned bounding box.
#pragma once

#include <algorithm>
#include <cmath>

#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>

namespace glint {

/// An axis-aligned box. A default-constructed box is empty (lo = +inf, hi = -inf), so that
/// extending it by any point gives that point.
template <class T>
struct AABB {
    /// Minimum corner; +inf on every axis while the box is empty.
    Vec3<T> lo{infinity<T>};
    /// Maximum corner; -inf on every axis while the box is empty.
    Vec3<T> hi{-infinity<T>};

    /// True when lo > hi on some axis (no point inside); a box around one point is not empty.
    bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
    /// Grows the box to the smallest one that also contains point `p`.
    void extend(const Vec3<T>& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    /// Grows the box to the smallest one that also contains box `b` (an empty `b` changes nothing).
    void extend(const AABB& b) { lo = glm::min(lo, b.lo); hi = glm::max(hi, b.hi); }
    /// Side lengths hi - lo per axis, or (0, 0, 0) for an empty box.
    Vec3<T> extent() const { return empty() ? Vec3<T>(0) : hi - lo; }
    /// Midpoint (lo + hi) / 2; not meaningful (NaN) for an empty box.
    Vec3<T> center() const { return (lo + hi) * T(0.5); }
    /// Total area of the six faces, 2 (xy + yz + zx) of the extent; 0 for an empty box.
    /// The cost weight of surface-area-heuristic builders.
    T surface_area() const {
        const Vec3<T> e = extent();
        return T(2) * (e.x * e.y + e.y * e.z + e.z * e.x);
    }
    /// Axis (0 = x, 1 = y, 2 = z) of the largest extent.
    int longest_axis() const { return max_abs_axis(extent()); }
    /// True when `p` lies inside or on the boundary; always false for an empty box or a NaN point.
    bool contains(const Vec3<T>& p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z &&
               p.z <= hi.z;
    }

    /// Slab test. On a hit, [t0, t1] is the overlap of the box with (tmin, tmax).
    /// Rays with zero direction components are handled by IEEE infinities; a NaN in the ray
    /// gives a miss.
    bool intersect(const Ray<T>& r, const Vec3<T>& inv_dir, T& t0, T& t1) const {
        t0 = r.tmin;
        t1 = r.tmax;
        for (int a = 0; a < 3; ++a) {
            // Near and far planes by the sign of the direction (not by comparing the two
            // distances, which a NaN would defeat), and max/min written so that a NaN slab
            // (0 * inf: the ray lies in that face) leaves the interval unchanged.
            const bool neg = std::signbit(inv_dir[a]);
            const T tn = ((neg ? hi[a] : lo[a]) - r.origin[a]) * inv_dir[a];
            const T tf = ((neg ? lo[a] : hi[a]) - r.origin[a]) * inv_dir[a];
            t0 = tn > t0 ? tn : t0;
            t1 = tf < t1 ? tf : t1;
        }
        return t0 <= t1;
    }
};

}  // namespace glint
