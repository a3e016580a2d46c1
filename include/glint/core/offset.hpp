// glint/core/offset.hpp: a hit on a triangle as shading needs it, and where a ray leaving it
// starts. The geometric normal is the triangle's own; the hit point interpolated from its
// vertices carries a bound on its rounding error, and the leaving ray's origin is moved along
// the normal past that bound, so that it cannot hit the surface it leaves (Pharr, Jakob,
// Humphreys 2023, sections 6.8.5-6.8.6). The same scene then renders the same image at any
// translation and scale float resolves.
//
//   const glint::Vec3<float> n = glint::geometric_normal(triangle);  // your triangle hit.id
//   const glint::SurfacePoint<float> p = glint::surface_point(triangle, hit.u, hit.v);
//   const glint::Ray<float> shadow{glint::offset_origin(p.x, p.err, n, to_light), to_light, 0, 1};
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glint/core/math.hpp>

namespace glint {

/// A hit point and the bound on its rounding error, per axis.
template <Scalar T>
struct SurfacePoint {
    Vec3<T> x;    ///< The point, as computed.
    Vec3<T> err;  ///< Per axis, a bound on |x - exact point| (>= 0).
};

/// gamma(n) = n u / (1 - n u), u = unit roundoff: the relative error bound of n roundings.
template <Scalar T>
constexpr T rounding_gamma(int n) {
    const T u = std::numeric_limits<T>::epsilon() / T(2);
    return T(n) * u / (T(1) - T(n) * u);
}

/// Bound on the rounding error, per axis, of a point computed from vertices whose largest
/// coordinate is m, and of the triangle tests' distances to their planes: gamma(16) m on
/// every axis. Interpolation alone errs by gamma(7) sum |b_i v_i| per axis (Pharr, Jakob,
/// Humphreys 2023, section 6.8.5), but an intersector mixes the axes (cross products), so
/// the floor at y = 0 of a box 1 wide still has distance errors of ulps of 1, not of 0.
template <Scalar T>
Vec3<T> coordinate_error(T m) {
    return Vec3<T>(rounding_gamma<T>(16) * m);
}

/// The unit normal (v1 - v0) x (v2 - v0) of triangle v, in its winding (not turned toward any
/// ray), computed in double precision; 0 for a triangle without area or with a non-finite vertex.
template <Scalar T>
Vec3<T> geometric_normal(const std::array<Vec3<T>, 3>& v) {
    const Vec3<double> n = glm::cross(Vec3<double>(v[1]) - Vec3<double>(v[0]), Vec3<double>(v[2]) - Vec3<double>(v[0]));
    const double length = glm::length(n);
    return length > 0 && std::isfinite(length) ? Vec3<T>(n / length) : Vec3<T>(0);
}

/// The point of triangle v at barycentrics (u, v) of vertices 1 and 2 (a hit's), and its
/// error bound. Unlike o + t d, whose error grows with the ray's length and origin, the
/// bound depends only on the triangle's own coordinates.
template <Scalar T>
SurfacePoint<T> surface_point(const std::array<Vec3<T>, 3>& v, T u, T w) {
    const Vec3<T> p = v[0] * (T(1) - u - w) + v[1] * u + v[2] * w;
    const Vec3<T> m = glm::max(glm::max(glm::abs(v[0]), glm::abs(v[1])), glm::abs(v[2]));
    return {p, coordinate_error(std::max({m.x, m.y, m.z}))};
}

/// Origin of a ray leaving point p (rounding error `err` per axis) of a surface with normal
/// n towards `dir`: p moved along n, to the side dir leaves to, past its error bound, and
/// each coordinate then rounded away from the surface (Pharr, Jakob, Humphreys 2023, section
/// 6.8.6). The offset scales with the coordinates' own rounding.
template <Scalar T>
Vec3<T> offset_origin(const Vec3<T>& p, const Vec3<T>& err, const Vec3<T>& n, const Vec3<T>& dir) {
    const T d = glm::dot(glm::abs(n), err) * T(2);
    const Vec3<T> offset = glm::dot(dir, n) >= T(0) ? n * d : -n * d;
    Vec3<T> po = p + offset;
    for (int i = 0; i < 3; ++i) {
        if (offset[i] > T(0)) po[i] = std::nextafter(po[i], infinity<T>);
        else if (offset[i] < T(0)) po[i] = std::nextafter(po[i], -infinity<T>);
    }
    return po;
}

}  // namespace glint
