// glint/intersection/wald.hpp: Wald's projection ray-triangle test.
//
// I. Wald, "Realtime Ray Tracing and Interactive Global Illumination" (PhD thesis, 2004),
// section 7.1: intersect the ray with the plane written as x_k + n_u x_u + n_v x_v = n_d
// (k the dominant axis of the normal, (u, v) the other two in cyclic order), then compute
// the barycentrics of the hit projected onto the (u, v) plane from two precomputed affine
// functions. 9 scalars plus the axis k. 000 section 4.1.1 cites it among the tests the IVM
// competes with. The coefficients are derived here by Cramer's rule on the projected edges
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

template <Scalar T>
struct Wald {
    using scalar_type = T;
    using RayData = detail::PlainRay<T>;
    static constexpr const char* name = "Wald";
    static constexpr bool uses_frame = false;
    static constexpr int field_count = 10;  // 9 coefficients + the axis, stored as a scalar

    T n_u = 0, n_v = 0, n_d = std::numeric_limits<T>::quiet_NaN();
    T beta_u = 0, beta_v = 0, beta_d = 0;    // beta  = barycentric of v1
    T gamma_u = 0, gamma_v = 0, gamma_d = 0; // gamma = barycentric of v2
    std::uint32_t k = 0;

    static Wald build(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
        Wald r;
        const Vec3d ec = b - a, eb = c - a;
        const Vec3d n = glm::cross(ec, eb);
        if (detail::degenerate_triangle(a, b, c)) return r;
        const int kk = max_abs_axis(n), u = (kk + 1) % 3, v = (kk + 2) % 3;
        const double nk = n[kk];  // = ec_u * eb_v - ec_v * eb_u
        r.k = static_cast<std::uint32_t>(kk);
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

    static RayData prepare(const Ray<T>& r) { return RayData::from(r); }

    bool intersect(const RayData& r, TriangleHit<T>& hit) const {
        const int u = mod3(k + 1), v = mod3(k + 2);
        const T t = (n_d - r.o[k] - n_u * r.o[u] - n_v * r.o[v]) /
                    (r.d[k] + n_u * r.d[u] + n_v * r.d[v]);
        if (!(t > r.tmin && t < r.tmax)) return false;
        const T hu = r.o[u] + t * r.d[u], hv = r.o[v] + t * r.d[v];
        const T beta = hu * beta_u + hv * beta_v + beta_d;
        if (!(beta >= T(0))) return false;
        const T gamma = hu * gamma_u + hv * gamma_v + gamma_d;
        if (!(gamma >= T(0) && beta + gamma <= T(1))) return false;
        hit.t = t;
        hit.u = beta;
        hit.v = gamma;
        return true;
    }

    void store(T* out) const {
        const T vals[10] = {n_u, n_v, n_d, beta_u, beta_v, beta_d, gamma_u, gamma_v, gamma_d, T(k)};
        std::copy(vals, vals + 10, out);
    }
    static Wald load(const SoaView<T, field_count>& s, std::size_t i) {
        Wald r;
        T* dst[9] = {&r.n_u, &r.n_v, &r.n_d, &r.beta_u, &r.beta_v, &r.beta_d,
                     &r.gamma_u, &r.gamma_v, &r.gamma_d};
        for (int f = 0; f < 9; ++f) *dst[f] = *s.field(f, i);
        r.k = static_cast<std::uint32_t>(*s.field(9, i));
        return r;
    }

    /// Branch-free kernel: the per-record axis selects ray components by blends, not gathers.
    static void batch(const SoaView<T, field_count>& s, std::size_t first, std::size_t n,
                      const RayData& r, T* ts, T* us, T* vs) {
        const T* f[10];
        for (int c = 0; c < 10; ++c) f[c] = s.field(c, first);
        for (std::size_t i = 0; i < n; ++i) {
            const T kf = f[9][i];
            const bool k0 = kf == T(0), k1 = kf == T(1);
            // (k, u, v) = (x, y, z), (y, z, x) or (z, x, y)
            const T ok_ = k0 ? r.o.x : (k1 ? r.o.y : r.o.z);
            const T ou = k0 ? r.o.y : (k1 ? r.o.z : r.o.x);
            const T ov = k0 ? r.o.z : (k1 ? r.o.x : r.o.y);
            const T dk = k0 ? r.d.x : (k1 ? r.d.y : r.d.z);
            const T du = k0 ? r.d.y : (k1 ? r.d.z : r.d.x);
            const T dv = k0 ? r.d.z : (k1 ? r.d.x : r.d.y);
            const T t = (f[2][i] - ok_ - f[0][i] * ou - f[1][i] * ov) /
                        (dk + f[0][i] * du + f[1][i] * dv);
            const T hu = ou + t * du, hv = ov + t * dv;
            const T beta = hu * f[3][i] + hv * f[4][i] + f[5][i];
            const T gamma = hu * f[6][i] + hv * f[7][i] + f[8][i];
            // Bitwise &, not &&: with && GCC vectorizes this loop only with AVX-512 masks.
            const bool ok = (t > r.tmin) & (t < r.tmax) & (beta >= T(0)) & (gamma >= T(0)) &
                            (beta + gamma <= T(1));
            ts[i] = ok ? t : infinity<T>;
            us[i] = beta;
            vs[i] = gamma;
        }
    }

private:
    static constexpr int mod3(std::uint32_t i) { return static_cast<int>(i % 3u); }
};

}  // namespace glint
