// glint/intersection/ivm.hpp: ray-triangle intersection with the inverse vertex matrix.
//
// Szécsi 2009, §4.1. With the triangle's vertices as the columns of V = [v0, v1, v2], the
// record is exactly the 9 scalars of M = V^-1 (the IVM):
//   - barycentrics of a point x are b = M x (eq. 4.8);
//   - every vertex satisfies [1,1,1] M v_i = 1, so the plane is q' . x = 1 with the row
//     q' = [1,1,1] M (eq. 4.12, the plane's point nearest the origin inverted in the unit
//     sphere); substituting x = o + t d gives t = (1 - q' . o) / (q' . d) (eq. 4.5 divided
//     by q . q);
//   - the hit is inside when all three barycentrics are >= 0: one three-way sign test.
// Repairs to the extracted text: eq. 4.5 is printed as (q.q - q.o)/(q.d), which is the same
// after dividing numerator and denominator by q.q; we use the q' (= q / q.q) form so that
// only the IVM is stored.
//
// Which 9 scalars: the rows m0, m1 of M and q' = m0 + m1 + m2 instead of m2, the same 9
// numbers up to an exact linear recombination. Summing the three rows in precision T
// cancels badly for slivers (each row is ~1/(L h) for a triangle of size L and height h,
// their sum ~1/L) and tilts the plane by eps * L / h; q' rounded once from double keeps the
// plane accurate. The third barycentric is then b2 = q' . x - b0 - b1 = 1 - b0 - b1 on the
// plane, and the sign test is unchanged.
//
// The frame. V is singular when the triangle's plane passes through the origin, and
// ill-conditioned when it passes near it. Szécsi 2009, §4.1 asks for a modelling space that
// avoids this; glint makes it automatic: the IVM's frame is OffsetFrames (frame.hpp), whose
// origins lie away from every plane of their group, and the ray is translated once per
// group. Degenerate (zero-area) triangles, and any record whose inverse is not finite, are
// stored as all zeros: then q' = 0, t = 1/0 is infinite and the test reports a miss, never
// a wrong hit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <type_traits>

#include <glint/core/math.hpp>
#include <glint/intersection/frame.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

/// The inverse-vertex-matrix test (Szécsi 2009, §4.1) as a TriangleIntersector: a record of
/// 9 scalars, in OffsetFrames so that no triangle plane passes near the frame origin.
template <Scalar T>
struct Ivm {
    using scalar_type = T;                ///< float or double: the record's and the test's precision.
    using RayData = detail::PlainRay<T>;  ///< The ray as it is: origin, direction, interval.
    using frame = OffsetFrames;           ///< Records live in per-group frames (frame.hpp).

    /// m[0], m[1]: rows 0 and 1 of M = [v0 v1 v2]^-1 (b_i = m[i] . x); m[2]: q' = [1,1,1] M.
    /// All zero for a degenerate triangle (never hits).
    Vec3<T> m[3]{};

    /// Inverts the vertex matrix in extended precision (double for float records, long
    /// double for double records), then rounds to T. Triangles whose area is below double
    /// rounding noise (|e1 x e2| <= 2^-60 * longest edge^2) are degenerate and never hit.
    static Ivm build(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
        Ivm r;
        if (detail::degenerate_triangle(a, b, c)) return r;
        using B = std::conditional_t<sizeof(T) < sizeof(double), double, long double>;
        const B v[3][3] = {{a.x, a.y, a.z}, {b.x, b.y, b.z}, {c.x, c.y, c.z}};
        // Rows of the inverse of the column matrix [a b c] are the cross products of pairs
        // of columns divided by the determinant: row i = v[i+1] x v[i+2] / det.
        B rows[3][3];
        for (int i = 0; i < 3; ++i) {
            const B* p = v[(i + 1) % 3];
            const B* q = v[(i + 2) % 3];
            rows[i][0] = p[1] * q[2] - p[2] * q[1];
            rows[i][1] = p[2] * q[0] - p[0] * q[2];
            rows[i][2] = p[0] * q[1] - p[1] * q[0];
        }
        const B det = v[0][0] * rows[0][0] + v[0][1] * rows[0][1] + v[0][2] * rows[0][2];
        if (!(det != B(0)) || !std::isfinite(double(det))) return r;
        for (int k = 0; k < 3; ++k) {
            r.m[0][k] = T(rows[0][k] / det);
            r.m[1][k] = T(rows[1][k] / det);
            r.m[2][k] = T((rows[0][k] + rows[1][k] + rows[2][k]) / det);
        }
        for (const auto& row : r.m)
            if (!all_finite(row)) return Ivm{};
        return r;
    }

    static RayData prepare(const Ray<T>& r) { return RayData::from(r); }  ///< Copies the ray's fields; no work.

    /// t from the plane q' . x = 1, then the three barycentrics' signs (bitwise &, not &&:
    /// without short-circuit branches the batch loop vectorizes).
    [[gnu::always_inline]] bool test(const RayData& r, T& t, T& u, T& v) const {
        const Vec3<T>& q = m[2];
        t = (T(1) - (q.x * r.o.x + q.y * r.o.y + q.z * r.o.z)) / (q.x * r.d.x + q.y * r.d.y + q.z * r.d.z);
        const T px = r.o.x + r.d.x * t, py = r.o.y + r.d.y * t, pz = r.o.z + r.d.z * t;
        const T b0 = m[0].x * px + m[0].y * py + m[0].z * pz;
        u = m[1].x * px + m[1].y * py + m[1].z * pz;
        v = T(1) - b0 - u;
        return (t > r.tmin) & (t < r.tmax) & (b0 >= T(0)) & (u >= T(0)) & (v >= T(0));
    }
};

}  // namespace glint
