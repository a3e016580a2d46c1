// glint/core/math.hpp: GLM aliases and the small vector helpers every folder uses.
#pragma once

#include <cmath>
#include <concepts>
#include <limits>

#include <glm/glm.hpp>

namespace glint {

/// Scalar types glint algorithms are instantiated for.
template <class T>
concept Scalar = std::same_as<T, float> || std::same_as<T, double>;

template <class T> using Vec2 = glm::vec<2, T, glm::defaultp>;
template <class T> using Vec3 = glm::vec<3, T, glm::defaultp>;
template <class T> using Vec4 = glm::vec<4, T, glm::defaultp>;
template <class T> using Mat3 = glm::mat<3, 3, T, glm::defaultp>;

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

template <class T> inline constexpr T infinity = std::numeric_limits<T>::infinity();
template <class T> inline constexpr T pi = T(3.14159265358979323846264338327950288);

/// Index (0, 1, 2) of the component with the largest absolute value.
template <class T>
constexpr int max_abs_axis(const Vec3<T>& v) {
    const T ax = std::abs(v.x), ay = std::abs(v.y), az = std::abs(v.z);
    return ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
}

/// True when every component is finite (no NaN, no infinity).
template <class T>
bool all_finite(const Vec3<T>& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Normalize, returning `fallback` for a zero, infinite or NaN vector instead of NaN.
template <class T>
Vec3<T> safe_normalize(const Vec3<T>& v, const Vec3<T>& fallback = Vec3<T>(0, 0, 1)) {
    const T len2 = glm::dot(v, v);
    if (!(len2 > T(0)) || !std::isfinite(len2)) return fallback;
    return v / std::sqrt(len2);
}

/// Orthonormal basis (b1, b2) completing the unit vector n to a right-handed frame.
/// Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 2017): branch-free apart
/// from the sign, no normalization, exact for n = +-z.
template <class T>
void orthonormal_basis(const Vec3<T>& n, Vec3<T>& b1, Vec3<T>& b2) {
    const T sign = std::copysign(T(1), n.z);
    const T a = T(-1) / (sign + n.z);
    const T b = n.x * n.y * a;
    b1 = Vec3<T>(T(1) + sign * n.x * n.x * a, sign * b, -sign * n.x);
    b2 = Vec3<T>(b, sign + n.y * n.y * a, -n.y);
}

}  // namespace glint
