// glint/core/optics.hpp: refraction at a smooth dielectric interface (Snell's law) and its
// Fresnel reflectance, written once for the path tracer's dielectrics (tracer/path_tracer.hpp)
// and Szécsi 2009, §6.4's glass shader (cones/glass.hpp). Formulas as in Pharr, Jakob, Humphreys
// 2023, sections 9.3 and 9.5.
#pragma once

#include <algorithm>
#include <cmath>

#include <glint/core/math.hpp>

namespace glint {

/// Refraction of the unit direction d at the unit normal n that faces it (dot(d, n) <= 0),
/// with relative index eta = n_from / n_to. Returns cos(theta_t) of the transmitted direction
/// and sets `out` to it (eta d + (eta cos_i - cos_t) n, unit up to rounding), or returns a
/// negative value under total internal reflection (and leaves `out` alone).
template <Scalar T>
T refract(const Vec3<T>& d, const Vec3<T>& n, T eta, Vec3<T>& out) {
    const T cos_i = -glm::dot(d, n);
    const T sin2_t = eta * eta * std::max(T(0), T(1) - cos_i * cos_i);
    if (sin2_t > T(1)) return T(-1);
    const T cos_t = std::sqrt(T(1) - sin2_t);
    out = d * eta + n * (eta * cos_i - cos_t);
    return cos_t;
}

/// Fresnel reflectance of a dielectric interface for unpolarized light: the mean of the s- and
/// p-polarized reflectances, from cos(theta_i), cos(theta_t) and eta = n_from / n_to.
template <Scalar T>
T fresnel_dielectric(T cos_i, T cos_t, T eta) {
    const T rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const T rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return T(0.5) * (rs * rs + rp * rp);
}

}  // namespace glint
