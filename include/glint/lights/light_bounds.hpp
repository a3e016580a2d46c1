// glint/lights/light_bounds.hpp: what a light tree knows about an emitter or a cluster of
// emitters (Conty Estevez and Kulla 2018, §4): a box holding them, their summed intensity
// scale phi, and two cones: the normals (axis w, half angle theta_o) and, around every normal,
// the directions they emit into (half angle theta_e). From these, importance(x, n) bounds from
// above, up to the constant phi stands for, the irradiance the cluster can send to a point x
// with normal n: phi cos(theta') / d^2 times the receiver's cos(theta_i'), theta' and theta_i'
// being the smallest angles any point of the box can give (the bounding sphere's subtended
// cone). pbrt-v4's LightBounds is the reference design.
//
// phi is an intensity scale, so that phi / d^2 is irradiance: the peak intensity I of a point
// light, and Le A for a polygon (the intensity along its normal). Emitters:
//   polygon   box of its vertices, w = normal, theta_o = 0, theta_e = pi / 2 (one-sided);
//   isotropic w arbitrary, theta_o = pi, theta_e = pi / 2;
//   cosine    w = axis, theta_o = 0, theta_e = pi / 2;
//   spot      w = axis, theta_o = the inner cone, theta_e = outer - inner.
#pragma once

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/math.hpp>
#include <glint/lights/light.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// A cone of directions: axis w, cos of its half angle (-1: the whole sphere).
template <Scalar T>
struct DirectionCone {
    Vec3<T> w{0, 0, 1};  ///< Unit axis.
    T cos_theta = T(1);  ///< Cosine of the half angle: 1 the axis alone, -1 the whole sphere.
};

namespace detail {

/// cos(max(0, a - b)) from the sines and cosines of a and b (angles in [0, pi]).
template <Scalar T>
T cos_sub_clamped(T sin_a, T cos_a, T sin_b, T cos_b) {
    return cos_a > cos_b ? T(1) : cos_a * cos_b + sin_a * sin_b;
}
/// sin(max(0, a - b)), likewise.
template <Scalar T>
T sin_sub_clamped(T sin_a, T cos_a, T sin_b, T cos_b) {
    return cos_a > cos_b ? T(0) : sin_a * cos_b - cos_a * sin_b;
}
template <Scalar T>
T sin_from_cos(T c) {
    return std::sqrt(std::max(T(0), T(1) - c * c));
}
template <Scalar T>
T safe_acos(T c) {
    return std::acos(std::clamp(c, T(-1), T(1)));
}

/// v rotated by angle about the unit axis k (Rodrigues).
template <Scalar T>
Vec3<T> rotate(const Vec3<T>& v, const Vec3<T>& k, T angle) {
    const T c = std::cos(angle), s = std::sin(angle);
    return v * c + glm::cross(k, v) * s + k * (glm::dot(k, v) * (T(1) - c));
}

}  // namespace detail

/// The smallest cone (of the two-cone family) holding cones a and b.
template <Scalar T>
DirectionCone<T> cone_union(const DirectionCone<T>& a, const DirectionCone<T>& b) {
    const T theta_a = detail::safe_acos(a.cos_theta), theta_b = detail::safe_acos(b.cos_theta);
    const T theta_d = detail::safe_acos(glm::dot(a.w, b.w));
    if (std::min(theta_d + theta_b, pi<T>) <= theta_a) return a;
    if (std::min(theta_d + theta_a, pi<T>) <= theta_b) return b;
    const T theta_o = (theta_a + theta_d + theta_b) * T(0.5);
    if (theta_o >= pi<T>) return {a.w, T(-1)};
    const Vec3<T> k = glm::cross(a.w, b.w);
    const T len = glm::length(k);
    if (!(len > T(0))) return {a.w, T(-1)};  // opposite axes
    const Vec3<T> w = safe_normalize(detail::rotate(a.w, k / len, theta_o - theta_a));
    return {w, std::cos(theta_o)};
}

/// Bounds of an emitter or a cluster of emitters (Conty Estevez and Kulla 2018, §4): box,
/// intensity scale and the normals' and emission cones; phi = 0 marks empty bounds.
template <Scalar T>
struct LightBounds {
    AABB<T> box;              ///< World-space box holding the emitters.
    T phi = T(0);             ///< Summed intensity scale (W/sr, luminance).
    Vec3<T> w{0, 0, 1};       ///< Unit axis of the normals' cone.
    T cos_theta_o = T(1);     ///< Cosine of the normals' cone's half angle theta_o.
    T cos_theta_e = T(0);     ///< Cosine of theta_e, the emission about each normal (0: a hemisphere).

    /// Bounds on the irradiance the emitters can send to x, whose surface's normal is n
    /// (reflecting side; n = 0: no receiver cosine). 0 only where none of them can reach x.
    /// (CompactLightBounds, below, evaluates it; a light tree keeps that form per node.)
    T importance(const Vec3<T>& x, const Vec3<T>& n) const;
};

/// LightBounds in the form importance() reads: the box's bounding sphere (centre c, radius r)
/// and the sine of the normals' cone, computed once, so that an evaluation costs four square
/// roots and one division (a light tree's descent evaluates two nodes per level).
template <Scalar T>
struct CompactLightBounds {
    Vec3<T> c{0};           ///< Centre of the box's bounding sphere.
    /// Bounding sphere's radius.
    T r = T(0), r2 = T(0);  ///< Its square.
    T phi = T(0);           ///< LightBounds::phi.
    Vec3<T> w{0, 0, 1};     ///< LightBounds::w.
    T cos_theta_o = T(1), sin_theta_o = T(0), cos_theta_e = T(0);
    /// \var cos_theta_o
    /// LightBounds::cos_theta_o.
    /// \var sin_theta_o
    /// Sine of theta_o, precomputed.
    /// \var cos_theta_e
    /// LightBounds::cos_theta_e.

    CompactLightBounds() = default;
    /// The compact form of b, its sphere and sine computed once.
    explicit CompactLightBounds(const LightBounds<T>& b)
        : c((b.box.lo + b.box.hi) * T(0.5)), phi(b.phi), w(b.w), cos_theta_o(b.cos_theta_o),
          sin_theta_o(detail::sin_from_cos(b.cos_theta_o)), cos_theta_e(b.cos_theta_e) {
        const Vec3<T> diag = b.box.hi - b.box.lo;
        r2 = glm::dot(diag, diag) * T(0.25);
        r = std::sqrt(r2);
    }

    /// LightBounds::importance: phi cos(theta') / d^2 times the receiver's cos(theta_i'), the
    /// angles reduced by the cone (half angle theta_b, sin theta_b = r / d) the sphere subtends.
    /// Every sine and cosine is a square root of d^2 minus a square, times 1 / d, so that the
    /// four square roots do not wait on each other.
    T importance(const Vec3<T>& x, const Vec3<T>& n) const {
        if (!(phi > T(0))) return T(0);
        const Vec3<T> d = x - c;
        const T d2 = glm::dot(d, d);
        // Inside the sphere every angle bound is 0 (cosines 1) and d^2 is floored at r^2.
        if (!(d2 > r2)) return cos_theta_e < T(1) ? phi / r2 : T(0);
        const T dw = glm::dot(w, d), dn = -glm::dot(d, n);
        const T root_d = std::sqrt(d2), root_b = std::sqrt(d2 - r2);
        const T root_w = std::sqrt(std::max(T(0), d2 - dw * dw)), root_i = std::sqrt(std::max(T(0), d2 - dn * dn));
        const T inv_d = T(1) / root_d;
        const T sin_b = r * inv_d, cos_b = root_b * inv_d;
        T cos_x = T(1), sin_x = T(0);  // cos, sin of max(0, theta_w - theta_o)
        if (cos_theta_o > T(-1)) {
            const T cos_w = dw * inv_d, sin_w = root_w * inv_d;
            cos_x = detail::cos_sub_clamped(sin_w, cos_w, sin_theta_o, cos_theta_o);
            sin_x = detail::sin_sub_clamped(sin_w, cos_w, sin_theta_o, cos_theta_o);
        }
        const T cos_p = detail::cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        if (cos_p <= cos_theta_e) return T(0);
        T imp = phi * std::max(cos_p, T(0)) * (inv_d * inv_d);
        if (glm::dot(n, n) > T(0))  // n = 0: dn = 0, root_i = d
            imp *= std::max(T(0), detail::cos_sub_clamped(root_i * inv_d, dn * inv_d, sin_b, cos_b));
        return imp;
    }
};

template <Scalar T>
T LightBounds<T>::importance(const Vec3<T>& x, const Vec3<T>& n) const {
    return CompactLightBounds<T>(*this).importance(x, n);
}

/// The bounds of two clusters together.
template <Scalar T>
LightBounds<T> bounds_union(const LightBounds<T>& a, const LightBounds<T>& b) {
    if (!(a.phi > T(0))) return b;
    if (!(b.phi > T(0))) return a;
    AABB<T> box = a.box;
    box.extend(b.box);
    const DirectionCone<T> cone = cone_union(DirectionCone<T>{a.w, a.cos_theta_o}, DirectionCone<T>{b.w, b.cos_theta_o});
    return {box, a.phi + b.phi, cone.w, cone.cos_theta, std::min(a.cos_theta_e, b.cos_theta_e)};
}

/// A point light's bounds (see the header's table).
template <Scalar T>
LightBounds<T> light_bounds(const PointLight<T>& l) {
    LightBounds<T> b;
    b.box.extend(l.position);
    b.phi = l.intensity.luminance();
    b.w = l.kind == PointLightKind::isotropic ? Vec3<T>(0, 0, 1) : l.axis;
    if (l.kind == PointLightKind::isotropic) {
        b.cos_theta_o = T(-1);
    } else if (l.kind == PointLightKind::spot) {
        b.cos_theta_o = l.cos_inner;
        b.cos_theta_e = std::cos(detail::safe_acos(l.cos_outer) - detail::safe_acos(l.cos_inner));
    }
    return b;
}

/// A polygon area light's bounds.
template <Scalar T>
LightBounds<T> light_bounds(const AreaLight<T>& l) {
    LightBounds<T> b;
    for (const auto& v : l.vertices) b.box.extend(v);
    b.phi = l.emission.luminance() * l.area;
    b.w = l.normal;
    return b;
}

/// Every emitter of the scene, in the order the lighting policies number them: the area
/// lights, then the point lights.
template <Scalar T>
std::vector<LightBounds<T>> scene_light_bounds(const Scene<T>& scene) {
    std::vector<LightBounds<T>> out;
    out.reserve(scene.area_lights.size() + scene.point_lights.size());
    for (const auto& l : scene.area_lights) out.push_back(light_bounds(l));
    for (const auto& l : scene.point_lights) out.push_back(light_bounds(l));
    return out;
}

}  // namespace glint
