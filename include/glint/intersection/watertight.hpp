// glint/intersection/watertight.hpp: the watertight ray-triangle test, glint's robustness
// reference.
//
// Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013). The ray is
// made the +z axis of a sheared frame (kz = its dominant axis, kx and ky the others, swapped
// when d[kz] < 0 to keep the winding), vertices are translated by the origin and sheared,
// and the three 2D edge functions U, V, W decide inside/outside. Two triangles sharing an
// edge compute the same edge function with opposite sign, so a ray can never pass between
// them, provided the edge functions' signs are exact.
//
// Exact signs. The paper recomputes U, V, W in double when one is exactly 0 (float). Here:
//  - T = float: U, V, W are always computed in double, where the products of two floats
//    are exact, so each edge function is one correctly rounded subtraction: exact sign,
//    whatever floating-point contraction (FMA) the compiler applies;
//  - T = double: Kahan's difference of products with fma, relative error <= 2 ulps
//    (Jeannerod, Louvet and Muller 2013), hence the exact sign, and exactly 0 iff the
//    products are equal.
// The shear of each vertex is computed the same way in every triangle that shares it, so
// shared edges agree. Edges and vertices are inclusive (a ray through a shared edge hits
// both triangles).
//
// Rays in (or parallel to) the triangle's plane. The edge functions are exact for the sheared
// vertices, but the shear itself rounds: each sheared coordinate is off by up to
// 2 eps (|p_k| + |s p_z|) (eps of T; the shear factors sx, sy are rounded too), which moves
// the determinant U + V + W by up to 12 eps M S (M: largest such magnitude, S: largest sheared
// coordinate). A determinant inside that bound is rounding noise: the ray is parallel to the
// plane within what T resolves, the exact answer is undefined (a miss), and which way the
// rounding went depends on the compiler (fused multiply-add or not). Such rays miss.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstddef>
#include <utility>

#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

namespace detail {
/// a*b - c*d with an exact sign (see the header comment).
inline double edge_function(float a, float b, float c, float d) {
    return double(a) * double(b) - double(c) * double(d);
}
inline double edge_function(double a, double b, double c, double d) {
    const double w = c * d;
    const double e = std::fma(-c, d, w);  // exactly w - c*d
    const double f = std::fma(a, b, -w);
    return f + e;
}
}  // namespace detail

/// The watertight test (Woop, Benthin and Wald 2013) as a TriangleIntersector: the record is
/// the three vertices (9 scalars), world coordinates; edges and vertices are inclusive.
template <Scalar T>
struct Watertight {
    using scalar_type = T;  ///< float or double: the record's precision (edge functions run in double).

    /// The ray's shear, computed once per ray by prepare().
    struct RayData {
        Vec3<T> o;        ///< Ray origin, as given.
        /// The origin's coordinate on axis kx.
        T okx, oky, okz;  ///< The origin's coordinate on axis kz.
        /// @var oky
        /// The origin's coordinate on axis ky.

        /// First axis of the sheared frame: kz + 1 mod 3 (kz + 2 when d[kz] < 0).
        int kx, ky, kz;   ///< The direction's dominant axis (largest |d|).
        /// @var ky
        /// Second axis of the sheared frame: kz + 2 mod 3 (kz + 1 when d[kz] < 0: the swap keeps the winding).

        /// Shear factor d[kx] / d[kz].
        T sx, sy, sz;     ///< Scale 1 / d[kz], which maps the sheared z to t.
        /// @var sy
        /// Shear factor d[ky] / d[kz].
        T tmin, tmax;     ///< Upper end of the open interval of t.
        /// @var tmin
        /// Lower end of the open interval of t.
    };

    Vec3<T> vtx[3]{};  ///< The vertices, frame coordinates; NaN for a degenerate triangle.

    /// Stores the vertices as given. A degenerate triangle (|e1 x e2| <= 2^-60 * longest
    /// edge^2, as for the other policies) is stored as NaN vertices, which every comparison
    /// rejects: after shearing, an exactly collinear triangle may look non-degenerate by a
    /// rounding error, and would then report hits.
    static Watertight build(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
        Watertight r;
        if (detail::degenerate_triangle(a, b, c)) {
            const T nan = std::numeric_limits<T>::quiet_NaN();
            for (auto& p : r.vtx) p = Vec3<T>(nan);
            return r;
        }
        r.vtx[0] = Vec3<T>(a);
        r.vtx[1] = Vec3<T>(b);
        r.vtx[2] = Vec3<T>(c);
        return r;
    }

    /// The shear of `r`: dominant axis, axis order and factors (Woop et al. 2013); a zero
    /// direction gives non-finite factors and every test misses.
    static RayData prepare(const Ray<T>& r) {
        RayData d;
        d.o = r.origin;
        d.kz = max_abs_axis(r.direction);
        d.kx = (d.kz + 1) % 3;
        d.ky = (d.kx + 1) % 3;
        if (r.direction[d.kz] < T(0)) std::swap(d.kx, d.ky);
        d.sx = r.direction[d.kx] / r.direction[d.kz];
        d.sy = r.direction[d.ky] / r.direction[d.kz];
        d.sz = T(1) / r.direction[d.kz];
        d.okx = r.origin[d.kx];
        d.oky = r.origin[d.ky];
        d.okz = r.origin[d.kz];
        d.tmin = r.tmin;
        d.tmax = r.tmax;
        return d;
    }

    /// The test on a record whose vertices' coordinates are ordered by the ray's axes
    /// (kx, ky, kz), as select_fields orders them. Bitwise (not short-circuit) logic keeps
    /// the batch loop branch-free.
    [[gnu::always_inline]] bool test(const RayData& r, T& t, T& u, T& v) const {
        T px[3], py[3], pz[3], sx[3], sy[3], m = 0;
        for (int i = 0; i < 3; ++i) {
            px[i] = vtx[i].x - r.okx;
            py[i] = vtx[i].y - r.oky;
            pz[i] = vtx[i].z - r.okz;
            sx[i] = px[i] - r.sx * pz[i];
            sy[i] = py[i] - r.sy * pz[i];
            m = std::max(m, shear_magnitude(px[i], py[i], pz[i], r));
        }
        const double e0 = detail::edge_function(sx[2], sy[1], sy[2], sx[1]);  // U: weight of v0
        const double e1 = detail::edge_function(sx[0], sy[2], sy[0], sx[2]);  // V: weight of v1
        const double e2 = detail::edge_function(sx[1], sy[0], sy[1], sx[0]);  // W: weight of v2
        const bool has_neg = (e0 < 0.0) | (e1 < 0.0) | (e2 < 0.0);
        const bool has_pos = (e0 > 0.0) | (e1 > 0.0) | (e2 > 0.0);
        const double det = e0 + e1 + e2;
        const double inv = 1.0 / det;
        t = T((e0 * double(r.sz * pz[0]) + e1 * double(r.sz * pz[1]) + e2 * double(r.sz * pz[2])) * inv);
        u = T(e1 * inv);
        v = T(e2 * inv);
        return !(has_neg & has_pos) & (std::abs(det) > noise(sx, sy, m)) & (t > r.tmin) & (t < r.tmax);
    }

    /// Orders a record's fields for test(): each vertex's coordinates on kx, ky, kz (the
    /// ray's axes are the same for every record: the fields are picked once per run).
    static void select_fields(const T* const (&in)[9], const RayData& r, const T* (&out)[9]) {
        for (int i = 0; i < 3; ++i) {
            out[3 * i] = in[3 * i + r.kx];
            out[3 * i + 1] = in[3 * i + r.ky];
            out[3 * i + 2] = in[3 * i + r.kz];
        }
    }

private:
    /// |p_k| + |s p_z| for the two sheared coordinates of a vertex p (translated by the origin).
    static T shear_magnitude(T px, T py, T pz, const RayData& r) {
        const T az = std::abs(pz);
        return std::max(std::abs(px) + std::abs(r.sx) * az, std::abs(py) + std::abs(r.sy) * az);
    }

    /// The determinant's rounding bound 12 eps M S of the header comment.
    static double noise(const T* x, const T* y, T m) {
        T s = 0;
        for (int i = 0; i < 3; ++i) s = std::max({s, std::abs(x[i]), std::abs(y[i])});
        return 12.0 * double(std::numeric_limits<T>::epsilon()) * double(m) * double(s);
    }
};

}  // namespace glint
