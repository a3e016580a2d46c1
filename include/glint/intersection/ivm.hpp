// glint/intersection/ivm.hpp: ray-triangle intersection with the inverse vertex matrix.
//
// 000 section 4.1, Szecsi's IVM test. With the triangle's vertices as the
// columns of V = [v0, v1, v2], the record is exactly the 9 scalars of M = V^-1 (the IVM):
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
// Which 9 scalars. We store the rows m0, m1 of M and q' = m0 + m1 + m2 instead of m2: the
// same 9 numbers up to an exact linear recombination, so still exactly the IVM. Why:
// summing the three rows in precision T cancels badly for slivers (each row is ~1/(L h)
// for a triangle of size L and height h, their sum ~1/L), which tilted the plane by
// eps * L / h and gave false hits hundreds of ulps from any edge in our sliver stress test.
// Rounding q' once from double keeps the plane accurate; the third barycentric is then
// b2 = q' . x - b0 - b1 = 1 - b0 - b1 on the plane, and the sign test is unchanged.
//
// The frame. V is singular when the triangle's plane passes through the origin, and
// ill-conditioned when it passes near it. 000 asks for a modelling space that avoids this;
// glint makes it automatic: records are built in a translated frame whose origin is chosen
// away from every plane of the block (detail::choose_frame in triangle.hpp: 26 candidates
// around the block's box, and blocks split until each group has quality >= 1/8), and the ray
// is translated once per group. A standalone Triangle<Ivm<T>> gets its own frame (centroid
// moved off the plane by the triangle's size). Degenerate (zero-area) triangles, and any
// record whose inverse is not finite, are stored as all zeros: then q' = 0, t = 1/0 is
// infinite and the test reports a miss, never a wrong hit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <type_traits>

#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

template <Scalar T>
struct Ivm {
    using scalar_type = T;
    using RayData = detail::PlainRay<T>;
    static constexpr const char* name = "Ivm";
    static constexpr bool uses_frame = true;
    static constexpr int field_count = 9;

    // m[0], m[1]: rows 0 and 1 of M = [v0 v1 v2]^-1 (b_i = m[i] . x); m[2]: q' = [1,1,1] M.
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

    static RayData prepare(const Ray<T>& r) { return RayData::from(r); }

    /// The test, written once for the scalar and the batch path: x = (m0, m1, q'), t from
    /// the plane q' . x = 1, then the three barycentrics' signs (bitwise &, not &&: without
    /// short-circuit branches the batch loop vectorizes on AVX2 too).
    [[gnu::always_inline]] static bool test(const T (&x)[field_count], const RayData& r, T& t, T& u, T& v) {
        const T qx = x[6], qy = x[7], qz = x[8];
        t = (T(1) - (qx * r.o.x + qy * r.o.y + qz * r.o.z)) / (qx * r.d.x + qy * r.d.y + qz * r.d.z);
        const T px = r.o.x + r.d.x * t, py = r.o.y + r.d.y * t, pz = r.o.z + r.d.z * t;
        const T b0 = x[0] * px + x[1] * py + x[2] * pz;
        u = x[3] * px + x[4] * py + x[5] * pz;
        v = T(1) - b0 - u;
        return (t > r.tmin) & (t < r.tmax) & (b0 >= T(0)) & (u >= T(0)) & (v >= T(0));
    }

    bool intersect(const RayData& r, TriangleHit<T>& hit) const { return detail::test_record(*this, r, hit); }

    void store(T* out) const {
        for (int k = 0; k < 9; ++k) out[k] = m[k / 3][k % 3];
    }
    static Ivm load(const SoaView<T, field_count>& v, std::size_t i) {
        Ivm r;
        for (int k = 0; k < 9; ++k) r.m[k / 3][k % 3] = *v.field(k, i);
        return r;
    }

    static void batch(const SoaView<T, field_count>& v, std::size_t first, std::size_t n,
                      const RayData& r, T* ts, T* us, T* vs) {
        detail::test_lanes<Ivm>(v, first, n, r, ts, us, vs);
    }
};

}  // namespace glint
