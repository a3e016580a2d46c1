// glint/intersection/wald.hpp: Wald's projection ray-triangle test.
//
// I. Wald, "Realtime Ray Tracing and Interactive Global Illumination" (PhD thesis, 2004),
// section 7.1: intersect the ray with the plane written as x_k + n_u x_u + n_v x_v = n_d
// (k the dominant axis of the normal, (u, v) the other two in cyclic order), then compute
// the barycentrics of the hit projected onto the (u, v) plane from two precomputed affine
// functions. 9 scalars plus the axis k. Szécsi 2009, §4.1.1 cites it among the tests the
// IVM competes with. The coefficients are derived here by Cramer's rule on the projected edges
// (c = v1 - v0, b = v2 - v0), whose 2x2 determinant is the normal's k component.
//
// A degenerate triangle (no dominant normal) gets n_d = NaN, so every t is NaN: a miss.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

/// Wald's projection test (I. Wald, PhD thesis 2004, §7.1) as a TriangleIntersector: 10
/// record scalars (the plane, two barycentric functions, the axis k), world coordinates.
template <Scalar T>
struct Wald {
    using scalar_type = T;                ///< float or double: the record's and the test's precision.
    using RayData = detail::PlainRay<T>;  ///< The ray as it is: origin, direction, interval.

    /// Plane x_k + n_u x_u + n_v x_v = n_d: the normal's u component over its k component.
    T n_u = 0, n_v = 0, n_d = std::numeric_limits<T>::quiet_NaN();  ///< The plane's offset; NaN for a degenerate triangle (always a miss).
    /// @var n_v
    /// The normal's v component over its k component.

    /// beta (barycentric of v1) = beta_u x_u + beta_v x_v + beta_d: coefficient of x_u.
    T beta_u = 0, beta_v = 0, beta_d = 0;    ///< beta's constant term.
    /// @var beta_v
    /// beta's coefficient of x_v.

    /// gamma (barycentric of v2) = gamma_u x_u + gamma_v x_v + gamma_d: coefficient of x_u.
    T gamma_u = 0, gamma_v = 0, gamma_d = 0; ///< gamma's constant term.
    /// @var gamma_v
    /// gamma's coefficient of x_v.
    T k = 0;  ///< The dominant axis 0, 1 or 2, as a scalar: a record holds scalars only.

    /// The record of triangle (a, b, c), given in double precision; rounded once to T.
    static Wald build(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
        Wald r;
        const Vec3d ec = b - a, eb = c - a;
        const Vec3d n = glm::cross(ec, eb);
        if (detail::degenerate_triangle(a, b, c)) return r;
        const int kk = max_abs_axis(n), u = (kk + 1) % 3, v = (kk + 2) % 3;
        const double nk = n[kk];  // = ec_u * eb_v - ec_v * eb_u
        r.k = T(kk);
        r.n_u = T(n[u] / nk);
        r.n_v = T(n[v] / nk);
        r.n_d = T(glm::dot(n, a) / nk);
        r.beta_u = T(eb[v] / nk);
        r.beta_v = T(-eb[u] / nk);
        r.beta_d = T((a[v] * eb[u] - a[u] * eb[v]) / nk);
        r.gamma_u = T(-ec[v] / nk);
        r.gamma_v = T(ec[u] / nk);
        r.gamma_d = T((a[u] * ec[v] - a[v] * ec[u]) / nk);
        return r;
    }

    static RayData prepare(const Ray<T>& r) { return RayData::from(r); }  ///< Copies the ray's fields; no work.

    /// The record's axis k selects the ray's components by selects, not by indexing (blends
    /// in the batch loop, not gathers); bitwise &, not &&, so that the loop vectorizes.
    [[gnu::always_inline]] bool test(const RayData& r, T& t, T& u, T& v) const {
        const bool k0 = k == T(0), k1 = k == T(1);
        // (k, u, v) = (x, y, z), (y, z, x) or (z, x, y)
        const T ok_ = k0 ? r.o.x : (k1 ? r.o.y : r.o.z);
        const T ou = k0 ? r.o.y : (k1 ? r.o.z : r.o.x);
        const T ov = k0 ? r.o.z : (k1 ? r.o.x : r.o.y);
        const T dk = k0 ? r.d.x : (k1 ? r.d.y : r.d.z);
        const T du = k0 ? r.d.y : (k1 ? r.d.z : r.d.x);
        const T dv = k0 ? r.d.z : (k1 ? r.d.x : r.d.y);
        t = (n_d - ok_ - n_u * ou - n_v * ov) / (dk + n_u * du + n_v * dv);
        const T hu = ou + t * du, hv = ov + t * dv;
        u = hu * beta_u + hv * beta_v + beta_d;
        v = hu * gamma_u + hv * gamma_v + gamma_d;
        return (t > r.tmin) & (t < r.tmax) & (u >= T(0)) & (v >= T(0)) & (u + v <= T(1));
    }
};

}  // namespace glint
