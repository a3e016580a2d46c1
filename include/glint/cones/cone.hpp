// glint/cones/cone.hpp: infinite cones that enclose bundles of rays, built incrementally.
//
// Szécsi 2009, §6.2: a bundle of coherent rays is enclosed in an infinite
// cone (apex a, unit axis x, half opening angle phi). Starting from the zero-angle cone of
// the first ray, every ray is added in two steps:
//   (a) if its direction r is outside the cone's solid angle (x . r < cos phi), the cone is
//       widened to the smallest cone holding both the old solid angle and r;
//   (b) if its origin o is outside the cone, the apex is translated along the far
//       generator e so that the near generator n passes through o.
//
// Repairs and derivations (the extracted formulas are garbled; each was derived again in
// the plane spanned by the axis x and the unit vector p perpendicular to x towards the new
// direction or point, and is checked by tests/test_cones.cpp):
//   (a) the cone-widening step gives q = ((x.r) x - r) / |(x.r) x - r| (= -p), the far generator
//       e = x cos phi + q sin phi, x_new = (e + r) / |e + r| and cos phi_new = x_new . r. With
//       theta the angle from x to r, e lies at angle -phi and r at +theta in that plane, so
//       the new cone is the bisector: phi_new = (theta + phi) / 2 and the axis rotates by
//       delta = (theta - phi) / 2 towards r. glint evaluates exactly that rotation,
//       x_new = x cos delta + p sin delta, with theta = 2 atan2(|r - x|, |r + x|), which
//       avoids the cancellation of e + r and of acos near 0 and pi. The text does not say
//       that the construction is only valid for phi_new < 90 degrees: when theta + phi >=
//       180 degrees the old cone contains -r and no cone of opening below 180 degrees holds
//       both (e + r then bisects the wrong arc). glint then falls back to the cone that
//       admits every ray (see below).
//   (b) the apex-translation step gives c = o - a, the same q with c for r, n = x cos phi - q sin phi,
//       g = c - (n.c) n, t = g^2 / (e.g) and a_new = a - e t. Here e.g < 0 (g points out of
//       the cone, e's part across n points in), so the printed t is negative and a - e t
//       would move the apex forwards: a minus sign was lost. Derived: with h = c.x and
//       rho = |c x x| the distance of o from the near generator line is
//       |g| = rho cos phi - h sin phi, and moving the apex back by s along e puts o on that
//       line when s sin(2 phi) = |g|, so s = |g| / sin(2 phi) = -g^2 / (e.g) and
//       a_new = a - e s. The text also misses two cases: (i) o lands on the *backward* half of
//       the line when h sin phi + rho cos phi < 0 (o behind the apex), and (ii) sin(2 phi)
//       -> 0 for phi -> 0 (parallel rays: a translation along e cannot help). In case (i),
//       and for phi near 90 degrees, glint translates along the axis instead by
//       s = |g| / sin phi (always valid for phi > 0). In case (ii) the opening is first
//       widened to ConeOptions::min_translate_angle (a wider cone with the same apex holds
//       the old one), so that parallel rays get a narrow cone with a distant apex.
//   Translating along any direction inside the cone (e, or x) keeps the old cone inside
//   the new one, and widening about the apex does too, so both steps are conservative.
//
// Order. Szécsi 2009 interleaves (a) and (b) ray by ray (ConeOrder::interleaved). Then an early
// translation made with a narrow opening pushes the apex far back, and a later widening
// about that distant apex makes the cone wide where the rays are. ConeOrder::directions_first
// (the default) runs step (a) over all rays, then step (b) over all origins with the final
// opening, so that the apex moves only as far as the final opening needs. Both are the
// same two steps of Szécsi 2009; only the order differs.
//
// Numerical safety. After either order a last pass makes the cone exact and safe: for the
// apex and axis found, it computes the smallest opening that holds every direction and
// every origin (tan(phi/2) = max |v - x| / |v + x| over the unit vectors v, stable for all
// angles), widened by a few ulps, and records `slack`, a distance that covers the rounding
// of apex and origins: every point of every enclosed ray lies within `slack` of the cone.
// This pass may also make the cone narrower than the incremental result (which
// overestimates). Rays with a non-finite origin or direction or a zero direction can hit
// nothing and are skipped. An opening above ConeOptions::max_half_angle (nearly opposite
// directions, incoherent bundles) gives the cone that admits every ray, Cone::everything(),
// rather than NaN or an unsafe cone: beyond 90 degrees a cone is not convex and rays that
// start inside it with directions inside its opening may leave it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>

namespace glint {

/// An infinite cone {p : angle(p - apex, axis) <= half_angle}, with half_angle <= 90
/// degrees, enlarged by `slack` (every point within `slack` of that set is enclosed).
/// `all` marks the cone that admits every ray (the fallback).
template <Scalar T>
struct Cone {
    Vec3<T> apex{0};        ///< Apex a, world space.
    Vec3<T> axis{0, 0, 1};  ///< Unit axis x, the direction the cone opens towards.
    T cos_half = T(1);   ///< cos(half_angle); -1 for Cone::everything()
    T sin_half = T(0);   ///< sin(half_angle)
    T half_angle = T(0); ///< radians, in [0, pi/2] (pi for Cone::everything())
    T slack = T(0);      ///< World-space distance the cone is enlarged by (covers rounding; 0 exact)
    bool all = false;    ///< True for Cone::everything(): every test against it passes.

    /// The cone that admits every ray (the numerically safe fallback).
    static Cone everything() {
        Cone c;
        c.cos_half = T(-1);
        c.sin_half = T(0);
        c.half_angle = pi<T>;
        c.all = true;
        return c;
    }
};

/// Which order the two steps of Szécsi 2009, §6.2 are applied in (see the header comment).
enum class ConeOrder : std::uint8_t { directions_first, interleaved };

/// Settings of enclosing_cone (and of the ray tiles' cones).
struct ConeOptions {
    ConeOrder order = ConeOrder::directions_first;  ///< Order of the widening and translation steps.
    /// Openings above this (radians, at most pi/2) give Cone::everything().
    double max_half_angle = 85.0 * pi<double> / 180.0;
    /// Smallest opening used to translate the apex (parallel rays with distinct origins).
    double min_translate_angle = 1.0 / 1024.0;

    /// Throws Error unless max_half_angle is in (0, pi/2] and min_translate_angle in
    /// (0, max_half_angle).
    void validate() const {
        if (!(max_half_angle > 0.0 && max_half_angle <= pi<double> / 2))
            throw Error("ConeOptions::max_half_angle must be in (0, pi/2], got " + std::to_string(max_half_angle));
        if (!(min_translate_angle > 0.0 && min_translate_angle < max_half_angle))
            throw Error("ConeOptions::min_translate_angle must be in (0, max_half_angle), got " +
                        std::to_string(min_translate_angle));
    }
};

/// Whether a ray can hit anything: finite origin, finite non-zero direction.
template <Scalar T>
bool ray_can_hit(const Ray<T>& r) {
    return all_finite(r.origin) && all_finite(r.direction) &&
           (r.direction.x != T(0) || r.direction.y != T(0) || r.direction.z != T(0));
}

namespace detail {

/// Unit vector along a finite non-zero v, without overflow or underflow of |v|^2 (scaled by
/// its largest component first: a direction of 1e-30 can still hit at t = 1e30).
template <class T>
Vec3<T> unit(const Vec3<T>& v) {
    const T m = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    return glm::normalize(v / m);
}

/// tan(angle(v, x) / 2) for unit vectors v, x: |v - x| / |v + x|, accurate for every angle
/// (no cancellation near 0 like 1 - cos, none near pi like acos). +inf for v = -x.
template <class T>
T tan_half_angle(const Vec3<T>& v, const Vec3<T>& x) {
    const T num = glm::length(v - x), den = glm::length(v + x);
    return den > T(0) ? num / den : infinity<T>;
}

/// Angle between unit vectors, in [0, pi], accurate everywhere.
template <class T>
T angle_between(const Vec3<T>& v, const Vec3<T>& x) {
    return T(2) * std::atan2(glm::length(v - x), glm::length(v + x));
}

/// Unit vector perpendicular to the unit vector x, along the part of v across x; any
/// perpendicular when v is (nearly) parallel to x.
template <class T>
Vec3<T> perpendicular_towards(const Vec3<T>& v, const Vec3<T>& x) {
    Vec3<T> b1, b2;
    orthonormal_basis(x, b1, b2);
    return safe_normalize(v - glm::dot(v, x) * x, b1);
}

/// Incremental state: apex, axis and half-angle phi with its cosine and sine.
template <class T>
struct ConeState {
    Vec3<T> apex{0}, axis{0, 0, 1};
    T phi = 0, cos_phi = 1, sin_phi = 0;
    bool all = false;

    void set_phi(T p) {
        phi = p;
        cos_phi = std::cos(p);
        sin_phi = std::sin(p);
    }
};

/// Step (a): widen the opening to hold the unit direction r (Szécsi 2009, §6.2, repaired
/// as described in the header comment).
template <class T>
void extend_to_direction(ConeState<T>& s, const Vec3<T>& r, const ConeOptions& opt) {
    if (s.all || glm::dot(s.axis, r) >= s.cos_phi) return;
    const T theta = angle_between(r, s.axis);
    if (!(theta > s.phi)) return;
    const T phi_new = T(0.5) * (theta + s.phi);
    if (!(phi_new <= T(opt.max_half_angle))) {
        s.all = true;
        return;
    }
    const T delta = T(0.5) * (theta - s.phi);
    const Vec3<T> p = perpendicular_towards(r, s.axis);
    s.axis = safe_normalize(s.axis * std::cos(delta) + p * std::sin(delta), s.axis);
    s.set_phi(phi_new);
}

/// Step (b): translate the apex so that the cone holds the point o (Szécsi 2009, §6.2,
/// repaired as described in the header comment).
template <class T>
void translate_to_point(ConeState<T>& s, const Vec3<T>& o, const ConeOptions& opt) {
    if (s.all) return;
    const Vec3<T> c = o - s.apex;
    const T h = glm::dot(c, s.axis);
    const T rho = glm::length(glm::cross(c, s.axis));
    if (rho * s.cos_phi - h * s.sin_phi <= T(0)) return;  // inside already
    if (s.phi < T(opt.min_translate_angle)) s.set_phi(T(opt.min_translate_angle));
    const T g = rho * s.cos_phi - h * s.sin_phi;  // distance of o from the near generator line
    if (!(g > T(0))) return;
    const T sin2 = T(2) * s.sin_phi * s.cos_phi;
    // A little extra (relative 2^-20) so that o ends strictly inside despite rounding; the
    // final pass makes the cone exact anyway.
    const T extra = T(1) + T(0x1p-20);
    if (h * s.sin_phi + rho * s.cos_phi > T(0) && sin2 > T(0.25)) {
        // Along the far generator e = x cos phi - p sin phi (p: towards o across the axis).
        const Vec3<T> p = (c - h * s.axis) / rho;
        const Vec3<T> e = s.axis * s.cos_phi - p * s.sin_phi;
        s.apex -= e * (g / sin2 * extra);
    } else {
        // Along the axis (o behind the apex, or phi near 0 or 90 degrees).
        s.apex -= s.axis * (g / s.sin_phi * extra);
    }
    if (!all_finite(s.apex)) s.all = true;
}

/// The final pass (see the header comment): exact opening for the apex and axis found,
/// rounded outwards, and the slack covering the rounding of positions.
template <class T, class Get>
Cone<T> finish_cone(const ConeState<T>& s, std::size_t n, Get&& ray_at, const ConeOptions& opt) {
    if (s.all || !all_finite(s.apex) || !all_finite(s.axis)) return Cone<T>::everything();
    constexpr T eps = std::numeric_limits<T>::epsilon();
    const T apex_norm = glm::length(s.apex);
    T tau = 0, reach = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const Ray<T>& r = ray_at(i);
        if (!ray_can_hit(r)) continue;
        tau = std::max(tau, tan_half_angle(unit(r.direction), s.axis));
        const Vec3<T> c = r.origin - s.apex;
        const T len = glm::length(c);
        if (!std::isfinite(len)) return Cone<T>::everything();  // |o - a| overflows
        // Rounding of o - a and of the apex: at most a few ulps of |o| + |a|.
        const T pos_err = T(8) * eps * (glm::length(r.origin) + apex_norm);
        reach = std::max(reach, pos_err);
        if (len > pos_err) tau = std::max(tau, tan_half_angle(c / len, s.axis));
        else reach = std::max(reach, len + pos_err);  // origin at the apex: covered by slack
    }
    if (!std::isfinite(tau)) return Cone<T>::everything();
    tau = tau * (T(1) + T(16) * eps) + T(16) * eps;
    const T phi = T(2) * std::atan(tau);
    if (!(phi <= T(opt.max_half_angle))) return Cone<T>::everything();
    Cone<T> cone;
    cone.apex = s.apex;
    cone.axis = s.axis;
    const T t2 = tau * tau;
    cone.cos_half = (T(1) - t2) / (T(1) + t2);
    cone.sin_half = T(2) * tau / (T(1) + t2);
    cone.half_angle = phi;
    cone.slack = reach;
    return cone;
}

/// Enclosing cone of the n rays ray_at(0 .. n-1) (Szécsi 2009, §6.2).
template <class T, class Get>
Cone<T> enclosing_cone_of(std::size_t n, Get&& ray_at, const ConeOptions& opt) {
    std::size_t first = 0;
    while (first < n && !ray_can_hit(ray_at(first))) ++first;
    if (first == n) {
        // Nothing can be hit: a zero-angle cone at the origin; it is never consulted for a
        // hit, but culls every triangle not on it.
        Cone<T> c;
        return c;
    }
    ConeState<T> s;
    s.apex = ray_at(first).origin;
    s.axis = unit(ray_at(first).direction);
    if (opt.order == ConeOrder::interleaved) {
        for (std::size_t i = first + 1; i < n && !s.all; ++i) {
            const Ray<T>& r = ray_at(i);
            if (!ray_can_hit(r)) continue;
            extend_to_direction(s, Vec3<T>(unit(r.direction)), opt);
            translate_to_point(s, r.origin, opt);
        }
    } else {
        for (std::size_t i = first + 1; i < n && !s.all; ++i) {
            const Ray<T>& r = ray_at(i);
            if (ray_can_hit(r)) extend_to_direction(s, Vec3<T>(unit(r.direction)), opt);
        }
        for (std::size_t i = first + 1; i < n && !s.all; ++i) {
            const Ray<T>& r = ray_at(i);
            if (ray_can_hit(r)) translate_to_point(s, r.origin, opt);
        }
    }
    return finish_cone(s, n, ray_at, opt);
}

}  // namespace detail

/// Enclosing cone of a bundle of rays (Szécsi 2009, §6.2): every ray that can hit anything
/// lies inside it (origin within `slack` of the cone, direction within the opening).
template <Scalar T>
Cone<T> enclosing_cone(std::span<const Ray<T>> rays, const ConeOptions& opt = {}) {
    opt.validate();
    return detail::enclosing_cone_of<T>(rays.size(), [&](std::size_t i) -> const Ray<T>& { return rays[i]; }, opt);
}

/// Enclosing cone of the rays rays[index[i]].
template <Scalar T>
Cone<T> enclosing_cone(std::span<const Ray<T>> rays, std::span<const std::uint32_t> index,
                       const ConeOptions& opt = {}) {
    opt.validate();
    return detail::enclosing_cone_of<T>(index.size(), [&](std::size_t i) -> const Ray<T>& { return rays[index[i]]; },
                                        opt);
}

}  // namespace glint
