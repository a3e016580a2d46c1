// glint/cones/sphere.hpp: bounding spheres of triangles and the cone-sphere test.
//
// Szécsi 2009, §6.3.1 stores, for every triangle, the centre and radius of an
// enclosing sphere next to its IVM; Szécsi 2009, §6.3.3 says they are
// computed when the mesh is loaded. glint uses the *minimal* enclosing sphere: for a
// triangle with an angle of 90 degrees or more it is the sphere on the longest edge as
// diameter; otherwise the circumsphere (centre in the triangle's plane, equidistant from the
// three vertices). It is computed in double and rounded outwards, so that the stored
// sphere holds the triangle exactly.
//
// Szécsi 2009, §6.3.4: the cone meets the sphere if
//     phi > arccos[(v - a) . x] - arcsin[r / |v - a|].
// Repair: the arccos argument must be divided by |v - a| (as printed it is not a cosine).
// With theta the angle from the axis to the centre and beta = arcsin(r / d) (d = |v - a|) the
// sphere's angular radius seen from the apex, the test is theta - beta < phi. glint uses the
// trig-free equivalent, the distance from the centre to the cone: with h = (v - a) . x and
// rho = |(v - a) x x|, the distance is rho cos phi - h sin phi (negative inside) when the
// nearest point is on a generator (rho sin phi + h cos phi >= 0), else the distance to the
// apex d; the cone meets the sphere when that distance is <= r. (d sin(theta - phi) <= r is
// theta - phi <= beta.) The text's test also misses the case of an apex inside the sphere
// (d < r, where arcsin is undefined): the distance form covers it. The radius is enlarged by
// the cone's slack and by a bound on the rounding of the test, so that the test in T never
// culls a sphere that the exact test keeps.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <glint/cones/cone.hpp>
#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

/// A sphere enclosing one triangle (Szécsi 2009, §6.3.1), tested against ray cones.
template <Scalar T>
struct BoundingSphere {
    Vec3<T> center{0};  ///< Centre, world space.
    T radius = T(-1);  ///< World units; negative: empty (nothing inside, meets no cone)
};

/// Minimal enclosing sphere of a triangle, rounded outwards to T. A triangle with a
/// non-finite vertex gets the empty sphere (it can never be hit).
template <Scalar T>
BoundingSphere<T> min_enclosing_sphere(const TriangleVertices<T>& tri) {
    BoundingSphere<T> s;
    if (!all_finite(tri[0]) || !all_finite(tri[1]) || !all_finite(tri[2])) return s;
    const Vec3d p[3] = {Vec3d(tri[0]), Vec3d(tri[1]), Vec3d(tri[2])};
    Vec3d center(0);
    bool done = false;
    // An angle of 90 degrees or more at vertex i (also a repeated vertex or collinear
    // points): the sphere on the opposite edge, which is the longest.
    for (int i = 0; i < 3 && !done; ++i) {
        const Vec3d& a = p[i];
        const Vec3d& b = p[(i + 1) % 3];
        const Vec3d& c = p[(i + 2) % 3];
        if (glm::dot(b - a, c - a) <= 0.0) {
            center = 0.5 * (b + c);
            done = true;
        }
    }
    if (!done) {
        // Acute: the circumcentre a + (|u|^2 (v x w) + |v|^2 (w x u)) / (2 |w|^2), w = u x v.
        const Vec3d u = p[1] - p[0], v = p[2] - p[0], w = glm::cross(u, v);
        const double w2 = glm::dot(w, w);
        center = p[0] + (glm::dot(u, u) * glm::cross(v, w) + glm::dot(v, v) * glm::cross(w, u)) / (2.0 * w2);
        if (!all_finite(center)) center = (p[0] + p[1] + p[2]) / 3.0;
    }
    s.center = Vec3<T>(center);
    const Vec3d cr(s.center);  // the centre as stored
    double r = 0.0;
    for (const Vec3d& q : p) r = std::max(r, glm::length(q - cr));
    // Round outwards: the double radius is within a few ulps of double; T(r) may round down.
    constexpr double eps_t = std::numeric_limits<T>::epsilon();
    s.radius = T(r * (1.0 + 4.0 * eps_t) + 4.0 * std::numeric_limits<double>::epsilon() * glm::length(cr));
    if (!std::isfinite(s.radius)) s.radius = infinity<T>;
    return s;
}

/// Sphere radius enlarged for the test: the cone's slack plus a bound on the rounding of
/// the test in T (terms proportional to the magnitudes that enter it).
template <Scalar T>
T cone_test_radius(const Cone<T>& cone, const BoundingSphere<T>& s) {
    constexpr T eps = std::numeric_limits<T>::epsilon();
    if (!(s.radius >= T(0))) return -infinity<T>;  // empty sphere
    return s.radius + cone.slack + T(16) * eps * (glm::length(s.center) + glm::length(cone.apex));
}

/// Whether the infinite cone meets the sphere (Szécsi 2009, §6.3.4, repaired: see above).
/// `radius` is the sphere's radius as enlarged by cone_test_radius (precomputed by the
/// ray-tile engine). Conservative: never false when an exact test would be true.
template <Scalar T>
bool cone_meets_sphere(const Cone<T>& cone, const Vec3<T>& center, T radius) {
    if (cone.all) return true;
    if (!(radius >= T(0))) return false;
    constexpr T eps = std::numeric_limits<T>::epsilon();
    const Vec3<T> w = center - cone.apex;
    const T h = glm::dot(w, cone.axis);
    const T rho = glm::length(glm::cross(w, cone.axis));
    const T r = radius + T(16) * eps * (rho + std::abs(h));
    if (rho * cone.sin_half + h * cone.cos_half >= T(0)) return rho * cone.cos_half - h * cone.sin_half <= r;
    return h * h + rho * rho <= r * r;
}

template <Scalar T>
bool cone_meets_sphere(const Cone<T>& cone, const BoundingSphere<T>& s) {
    return cone_meets_sphere(cone, s.center, cone_test_radius(cone, s));
}

}  // namespace glint
