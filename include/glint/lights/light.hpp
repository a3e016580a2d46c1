// glint/lights/light.hpp: the point emitters of many-light scenes, each with its intensity
// profile and the cone of directions it emits into:
//   isotropic  I in every direction (a point light);
//   spot       I cos(theta) inside a cone around its axis, falling off smoothly to 0 between
//              the inner and the outer cone (a smoothstep in cos theta): the profile of
//              Blender's spot lights in Cycles 3.4 (measured: tools/peer_cycles.py exports
//              them with spot_size = 2 acos(cos_outer) and spot_blend = (cos_inner -
//              cos_outer) / (1 - cos_outer)); pbrt-v4's spot light has no cos theta;
//   cosine     I cos(theta) in the hemisphere around its axis: an oriented point, what a small
//              area light or a virtual point light is from afar (Fernandez 2004, §5.1, splits
//              area lights into such points; Walter et al. 2005 call them oriented lights).
// Polygon area lights are AreaLight in tracer/scene.hpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// A point emitter's intensity profile (the header's table).
enum class PointLightKind : std::uint8_t { isotropic, spot, cosine };

/// A point emitter: position, intensity and profile. An aggregate; build one with isotropic(),
/// spot() or oriented(), and check it with validate().
template <Scalar T>
struct PointLight {
    Vec3<T> position{0};     ///< World-space position.
    Rgb<T> intensity{T(0)};  ///< W/sr per band: everywhere (isotropic), along the axis (spot, cosine).
    PointLightKind kind = PointLightKind::isotropic;  ///< The intensity profile.
    Vec3<T> axis{0, 0, -1};  ///< Unit; spot and cosine lights.
    T cos_outer = T(-1);     ///< Spot: cosine of the outer cone's half angle; no light beyond it.
    T cos_inner = T(-1);     ///< Spot: cosine of the inner cone's half angle; full intensity inside it.

    /// An isotropic point light at p of intensity i (W/sr per band).
    static PointLight isotropic(const Vec3<T>& p, const Rgb<T>& i) { return {p, i}; }
    /// A spot light; outer and inner are the cones' half angles in radians (inner <= outer),
    /// both at most pi / 2 (beyond, the cos theta factor would turn negative).
    static PointLight spot(const Vec3<T>& p, const Vec3<T>& axis, const Rgb<T>& i, T outer, T inner) {
        return {p, i, PointLightKind::spot, safe_normalize(axis), std::cos(outer), std::cos(std::min(inner, outer))};
    }
    /// An oriented (cosine-profile) point at p emitting i cos(theta) around `normal`
    /// (normalized here; a zero or non-finite normal becomes +z).
    static PointLight oriented(const Vec3<T>& p, const Vec3<T>& normal, const Rgb<T>& i) {
        return {p, i, PointLightKind::cosine, safe_normalize(normal), T(0), T(1)};
    }

    /// The profile in unit direction w (leaving the light): I(w) = intensity * falloff(w).
    T falloff(const Vec3<T>& w) const {
        if (kind == PointLightKind::isotropic) return T(1);
        const T c = glm::dot(axis, w);
        if (kind == PointLightKind::cosine) return std::max(c, T(0));
        if (c >= cos_inner) return c;
        if (c <= cos_outer) return T(0);
        const T s = (c - cos_outer) / (cos_inner - cos_outer);
        return c * s * s * (T(3) - T(2) * s);
    }
    /// The intensity I(w) in unit direction w leaving the light, W/sr per band.
    Rgb<T> intensity_towards(const Vec3<T>& w) const { return intensity * falloff(w); }

    /// The cosine of the half angle of the cone around `axis` outside which falloff is 0
    /// (-1: the whole sphere): the emission bound of a light tree's node (Conty Estevez and
    /// Kulla 2018's theta_e).
    T cos_emission() const {
        if (kind == PointLightKind::isotropic) return T(-1);
        return kind == PointLightKind::cosine ? T(0) : cos_outer;
    }

    /// The solid-angle integral of falloff: power = intensity * measure(). For a spot light,
    /// 2 pi times the integral of c S over c in [cos_outer, 1] (S the smoothstep, 1 above
    /// cos_inner): (1 - ci^2) / 2 + w (co / 2 + 0.35 w), w = ci - co, since the integrals of S
    /// and t S over [0, 1] are 1/2 and 3/4 - 2/5.
    T measure() const {
        if (kind == PointLightKind::isotropic) return T(4) * pi<T>;
        if (kind == PointLightKind::cosine) return pi<T>;
        const T w = cos_inner - cos_outer;
        return T(2) * pi<T> * ((T(1) - cos_inner * cos_inner) * T(0.5) + w * (cos_outer * T(0.5) + T(0.35) * w));
    }
    /// The emitted power, W per band: intensity times measure().
    Rgb<T> power() const { return intensity * measure(); }

    /// Throws glint::Error naming light `index` for a non-finite position, a negative or
    /// non-finite intensity, a zero axis or an inner cone wider than the outer one.
    void validate(std::size_t index) const {
        const std::string at = "light " + std::to_string(index);
        if (!all_finite(position)) throw Error(at + ": position is not finite");
        if (!intensity.is_finite() || intensity.min() < T(0)) throw Error(at + ": intensity is negative or not finite");
        if (kind == PointLightKind::isotropic) return;
        if (!all_finite(axis) || std::abs(glm::length(axis) - T(1)) > T(1e-3)) throw Error(at + ": axis is not a unit vector");
        if (kind == PointLightKind::spot && !(cos_outer <= cos_inner && cos_outer >= T(0) && cos_inner <= T(1)))
            throw Error(at + ": spot cones need 0 <= cos_outer <= cos_inner <= 1, got " + std::to_string(cos_outer) + ", " +
                        std::to_string(cos_inner));
    }
};

}  // namespace glint
