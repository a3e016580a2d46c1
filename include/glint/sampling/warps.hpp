// glint/sampling/warps.hpp: maps from the unit square to directions and surface points, each
// with the density it produces.
//
// Szécsi 2009, §1.3 samples directions by BRDF (cosine-weighted hemisphere) and
// light sources by area (uniform point on a triangle or polygon, density 1/area); Szécsi 2009, §3.2
// samples points uniformly on a polygon light. Standard constructions:
// Shirley-Chiu concentric disk + Malley's method for the cosine hemisphere (pdf cos(theta)/pi),
// Archimedes' projection for the uniform sphere (1/4pi) and hemisphere (1/2pi), the square-root
// warp for triangles (barycentrics b0 = 1 - sqrt(u0), b1 = u1 sqrt(u0)), and area-weighted fan
// triangulation for convex polygons. Inputs in [0,1)^2; outputs never NaN for inputs in [0,1].
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>

namespace glint {

/// Orthonormal frame with n as local z.
template <Scalar T>
struct Frame {
    /// First tangent (local x), unit.
    Vec3<T> s, t, n;  ///< Normal (local z), unit.
    /// \var t
    /// Second tangent (local y), unit, completing a right-handed basis (s, t, n).

    /// The frame with local z = `normal` (unit; not normalized here) and tangents from
    /// orthonormal_basis().
    static Frame from_normal(const Vec3<T>& normal) {
        Frame f;
        f.n = normal;
        orthonormal_basis(normal, f.s, f.t);
        return f;
    }
    /// Local coordinates v to world space: v.x s + v.y t + v.z n.
    Vec3<T> to_world(const Vec3<T>& v) const { return v.x * s + v.y * t + v.z * n; }
    /// World-space v to local coordinates (its dot products with s, t, n).
    Vec3<T> to_local(const Vec3<T>& v) const {
        return Vec3<T>(glm::dot(v, s), glm::dot(v, t), glm::dot(v, n));
    }
};

/// Shirley-Chiu concentric map of [0,1)^2 onto the unit disk (area preserving up to pi).
template <Scalar T>
Vec2<T> square_to_concentric_disk(const Vec2<T>& u) {
    const T a = T(2) * u.x - T(1), b = T(2) * u.y - T(1);
    if (a == T(0) && b == T(0)) return Vec2<T>(0, 0);
    T r, phi;
    if (std::abs(a) > std::abs(b)) {
        r = a;
        phi = (pi<T> / T(4)) * (b / a);
    } else {
        r = b;
        phi = (pi<T> / T(2)) - (pi<T> / T(4)) * (a / b);
    }
    return Vec2<T>(r * std::cos(phi), r * std::sin(phi));
}

/// Cosine-weighted direction about +z (Malley's method); density cosine_hemisphere_pdf.
template <Scalar T>
Vec3<T> square_to_cosine_hemisphere(const Vec2<T>& u) {
    const Vec2<T> d = square_to_concentric_disk(u);
    const T z = std::sqrt(std::max(T(0), T(1) - d.x * d.x - d.y * d.y));
    return Vec3<T>(d.x, d.y, z);
}
/// Density cos(theta)/pi per steradian of square_to_cosine_hemisphere; 0 below the horizon.
template <Scalar T>
T cosine_hemisphere_pdf(T cos_theta) {
    return cos_theta > T(0) ? cos_theta / pi<T> : T(0);
}

namespace detail {
/// Unit vector with height z and azimuth 2 pi v (Archimedes: uniform z gives uniform area).
template <Scalar T>
Vec3<T> direction_from_height(T z, T v) {
    const T r = std::sqrt(std::max(T(0), T(1) - z * z));
    const T phi = T(2) * pi<T> * v;
    return Vec3<T>(r * std::cos(phi), r * std::sin(phi), z);
}
}  // namespace detail

/// Direction about +z with density (e+1)/(2 pi) cos^e(theta) (a normalized Phong lobe); e >= 0.
template <Scalar T>
Vec3<T> square_to_cosine_power_hemisphere(const Vec2<T>& u, T exponent) {
    // CDF of cos(theta): 1 - cos^(e+1); cos = (1 - u)^(1/(e+1)) keeps z > 0 for u < 1.
    return detail::direction_from_height(std::pow(T(1) - u.x, T(1) / (exponent + T(1))), u.y);
}
/// Density (e+1)/(2 pi) cos^e(theta) per steradian of square_to_cosine_power_hemisphere; 0
/// below the horizon.
template <Scalar T>
T cosine_power_hemisphere_pdf(T cos_theta, T exponent) {
    return cos_theta > T(0)
               ? (exponent + T(1)) / (T(2) * pi<T>) * std::pow(cos_theta, exponent)
               : T(0);
}

/// Uniform direction on the unit sphere; density 1/(4 pi).
template <Scalar T>
Vec3<T> square_to_uniform_sphere(const Vec2<T>& u) {
    return detail::direction_from_height(T(1) - T(2) * u.x, u.y);
}
/// Density 1/(4 pi) per steradian of square_to_uniform_sphere.
template <Scalar T>
constexpr T uniform_sphere_pdf() {
    return T(1) / (T(4) * pi<T>);
}

/// Uniform direction on the hemisphere about +z; density 1/(2 pi).
template <Scalar T>
Vec3<T> square_to_uniform_hemisphere(const Vec2<T>& u) {
    return detail::direction_from_height(T(1) - u.x, u.y);  // z in (0, 1]
}
/// Density 1/(2 pi) per steradian of square_to_uniform_hemisphere.
template <Scalar T>
constexpr T uniform_hemisphere_pdf() {
    return T(1) / (T(2) * pi<T>);
}

/// Uniform barycentrics (b0, b1) on a triangle (b2 = 1 - b0 - b1).
template <Scalar T>
Vec2<T> square_to_uniform_triangle(const Vec2<T>& u) {
    const T su = std::sqrt(u.x);
    return Vec2<T>(T(1) - su, u.y * su);
}

/// Uniform point on triangle (a, b, c); density 1 / triangle_area(a, b, c).
template <Scalar T>
Vec3<T> sample_triangle(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c, const Vec2<T>& u) {
    const Vec2<T> bc = square_to_uniform_triangle(u);
    return bc.x * a + bc.y * b + (T(1) - bc.x - bc.y) * c;
}
/// Area of triangle (a, b, c), half the length of the cross product of two edges.
template <Scalar T>
T triangle_area(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c) {
    return T(0.5) * glm::length(glm::cross(b - a, c - a));
}

/// Uniform points on a planar convex polygon (vertices in order). The fan triangles from vertex
/// 0 are chosen by area with u.x, which is then rescaled and reused; density 1 / area().
template <Scalar T>
class PolygonSampler {
public:
    PolygonSampler() = default;
    /// Copies `vertices` (>= 3, coplanar, convex, in order) and builds the fan's area CDF.
    /// Throws Error for fewer than 3 vertices or a zero or non-finite area.
    explicit PolygonSampler(std::span<const Vec3<T>> vertices)
        : vertices_(vertices.begin(), vertices.end()) {
        if (vertices.size() < 3)
            throw Error("glint::PolygonSampler: a polygon needs at least 3 vertices, got " +
                        std::to_string(vertices.size()));
        cdf_.resize(vertices.size() - 2);
        T total = 0;
        Vec3<T> normal(0);
        for (std::size_t i = 1; i + 1 < vertices.size(); ++i) {
            const Vec3<T> c = glm::cross(vertices[i] - vertices[0], vertices[i + 1] - vertices[0]);
            normal += c;
            total += T(0.5) * glm::length(c);
            cdf_[i - 1] = total;
        }
        if (!(total > T(0)) || !std::isfinite(total))
            throw Error("glint::PolygonSampler: degenerate polygon (zero or non-finite area)");
        for (T& c : cdf_) c /= total;
        cdf_.back() = T(1);
        area_ = total;
        normal_ = safe_normalize(normal);
    }

    /// Area of the polygon (sum of its fan triangles).
    T area() const { return area_; }
    /// Density 1 / area() per unit area of sample().
    T pdf() const { return T(1) / area_; }
    /// Unit normal, oriented by the vertex order (counter-clockwise seen from its side).
    const Vec3<T>& normal() const { return normal_; }
    /// The vertices as given (a view valid while the sampler lives).
    std::span<const Vec3<T>> vertices() const { return vertices_; }

    /// Uniform point on the polygon from u in [0, 1)^2: u.x picks the fan triangle by area and is
    /// rescaled to sample inside it. Cost linear in the vertex count.
    Vec3<T> sample(Vec2<T> u) const {
        std::size_t i = 0;
        while (i + 1 < cdf_.size() && u.x >= cdf_[i]) ++i;
        const T lo = i == 0 ? T(0) : cdf_[i - 1];
        u.x = std::min((u.x - lo) / (cdf_[i] - lo), T(1));
        return sample_triangle(vertices_[0], vertices_[i + 1], vertices_[i + 2], u);
    }

private:
    std::vector<Vec3<T>> vertices_;
    std::vector<T> cdf_;
    T area_ = 0;
    Vec3<T> normal_{0, 0, 1};
};

}  // namespace glint
