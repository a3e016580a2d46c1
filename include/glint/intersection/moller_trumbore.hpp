// glint/intersection/moller_trumbore.hpp: the Moller-Trumbore ray-triangle test.
//
// Moller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection" (JGT 1997): solve
// o + t d = (1 - u - v) v0 + u v1 + v v2 by Cramer's rule with two cross products and no
// precomputed plane. Szécsi 2009, §4.1.1 compares the IVM test against it as
// "the fastest known ... working without precomputed values". Our record keeps v0 and the
// two edges e1 = v1 - v0, e2 = v2 - v0 (9 scalars, the same footprint as the IVM), which is
// how it is usually deployed and the strongest version of this baseline.
//
// No epsilon: the classic |det| < 1e-8 rejection is scale dependent (it drops small but
// valid triangles). Only det == 0 (ray parallel to the plane, or a degenerate triangle) is
// a miss; every comparison is written so that NaN fails it.
#pragma once

#include <algorithm>
#include <cstddef>

#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

/// The Moller-Trumbore test (Moller and Trumbore 1997) as a TriangleIntersector: a record
/// of 9 scalars, no epsilon, world coordinates (IdentityFrame).
template <Scalar T>
struct MollerTrumbore {
    using scalar_type = T;                ///< float or double: the record's and the test's precision.
    using RayData = detail::PlainRay<T>;  ///< The ray as it is: origin, direction, interval.

    /// Vertex 0, in the frame's coordinates.
    Vec3<T> v0{0}, e1{0}, e2{0};  ///< Edge v2 - v0 (zero for a degenerate triangle).
    /// @var e1
    /// Edge v1 - v0 (zero for a degenerate triangle).

    /// Degenerate triangles (|e1 x e2| <= 2^-60 * longest edge^2) get zero edges: det = 0,
    /// never a hit.
    static MollerTrumbore build(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
        MollerTrumbore r;
        r.v0 = Vec3<T>(a);
        if (detail::degenerate_triangle(a, b, c)) return r;
        r.e1 = Vec3<T>(b - a);
        r.e2 = Vec3<T>(c - a);
        return r;
    }

    static RayData prepare(const Ray<T>& r) { return RayData::from(r); }  ///< Copies the ray's fields; no work.

    /// Which of the batch_width records of one block (`block`: its field 0 of record 0, the
    /// SoaView layout) can hit: those with a non-zero edge (degenerate triangles and a
    /// leaf's padding never do). A packet's leaf test (trees/packet_leaf.hpp) skips the rest.
    static unsigned live_records(const T* block) {
        constexpr int W = int(batch_width);
        unsigned live = 0;
        for (int i = 0; i < W; ++i) {
            bool zero = true;
            for (int f = 3; f < 9; ++f) zero &= block[f * W + i] == T(0);  // e1, e2
            live |= unsigned(!zero) << i;
        }
        return live;
    }

    /// Cramer's rule; bitwise &, not &&, so that the batch loop has no branches and
    /// vectorizes.
    [[gnu::always_inline]] bool test(const RayData& r, T& t, T& u, T& v) const {
        const T e1x = e1.x, e1y = e1.y, e1z = e1.z;
        const T e2x = e2.x, e2y = e2.y, e2z = e2.z;
        const T px = r.d.y * e2z - r.d.z * e2y;
        const T py = r.d.z * e2x - r.d.x * e2z;
        const T pz = r.d.x * e2y - r.d.y * e2x;
        const T det = e1x * px + e1y * py + e1z * pz;
        const T inv = T(1) / det;
        const T sx = r.o.x - v0.x, sy = r.o.y - v0.y, sz = r.o.z - v0.z;
        u = (sx * px + sy * py + sz * pz) * inv;
        const T qx = sy * e1z - sz * e1y;
        const T qy = sz * e1x - sx * e1z;
        const T qz = sx * e1y - sy * e1x;
        v = (r.d.x * qx + r.d.y * qy + r.d.z * qz) * inv;
        t = (e2x * qx + e2y * qy + e2z * qz) * inv;
        return (det != T(0)) & (u >= T(0)) & (v >= T(0)) & (u + v <= T(1)) & (t > r.tmin) & (t < r.tmax);
    }
};

}  // namespace glint
