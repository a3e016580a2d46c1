// glint/photons/surface_area.hpp: the area of a surface inside a gather sphere, so that a
// density estimate near a surface's edge divides by the area its photons can lie on rather
// than by the whole disc pi R^2 (the disc reaching past a wall's edge or into a corner holds
// no photons of the surface there, and the estimate is dark by the missing share: the
// estimate assumes the surface locally flat and filling the disc, Jensen 2001, ch. 7). The
// surface is a visible point's surface group (photons/surface_groups.hpp, Larsen 2004, ch. 8:
// triangles joined across edges of small dihedral angle), and its area inside the sphere is
// the sum over its triangles of each triangle's intersection with the disc the sphere cuts
// from the triangle's plane, computed exactly (circle and polygon: the pieces of each edge
// inside the circle add triangle areas, the pieces outside add circular sectors).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <glint/core/buckets.hpp>
#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/photons/surface_groups.hpp>

namespace glint {

namespace detail {

/// Signed area of the intersection of the disc of radius r about the origin with the triangle
/// (origin, a, b) in the plane: positive when a to b turns counter-clockwise.
inline double disc_wedge_area(double ax, double ay, double bx, double by, double r) {
    const double dx = bx - ax, dy = by - ay;
    // Points a + t (b - a), t in (0, 1), on the circle: the edge's pieces inside and outside.
    const double qa = dx * dx + dy * dy, qb = 2 * (ax * dx + ay * dy), qc = ax * ax + ay * ay - r * r;
    double ts[4] = {0, 0, 0, 1};
    int count = 1;
    const double disc = qb * qb - 4 * qa * qc;
    if (qa > 0 && disc > 0) {
        const double sq = std::sqrt(disc);
        for (const double t : {(-qb - sq) / (2 * qa), (-qb + sq) / (2 * qa)})
            if (t > 0 && t < 1) ts[count++] = t;
    }
    ts[count++] = 1;
    double area = 0;
    for (int i = 0; i + 1 < count; ++i) {
        const double px = ax + ts[i] * dx, py = ay + ts[i] * dy, qx = ax + ts[i + 1] * dx, qy = ay + ts[i + 1] * dy;
        const double mx = (px + qx) / 2, my = (py + qy) / 2, cross = px * qy - py * qx;
        if (mx * mx + my * my <= r * r) area += cross / 2;                      // inside: a triangle
        else area += r * r * std::atan2(cross, px * qx + py * qy) / 2;           // outside: a sector
    }
    return area;
}

}  // namespace detail

/// Area of triangle t inside the sphere about x of radius r: the triangle's intersection with
/// the disc the sphere cuts from its plane (0 when the plane is r or more away).
template <Scalar T>
double sphere_triangle_area(const TriangleVertices<T>& t, const Vec3<T>& x, double r) {
    const glm::dvec3 a(t[0]), b(t[1]), c(t[2]), p(x);
    const glm::dvec3 cr = glm::cross(b - a, c - a);
    const double len = glm::length(cr);
    if (!(len > 0) || !(r > 0)) return 0;
    const glm::dvec3 n = cr / len;
    const double h = glm::dot(p - a, n), rho2 = r * r - h * h;
    if (!(rho2 > 0)) return 0;
    const glm::dvec3 centre = p - h * n, u = glm::normalize(b - a), v = glm::cross(n, u);
    auto local = [&](const glm::dvec3& q) { return glm::dvec2(glm::dot(q - centre, u), glm::dot(q - centre, v)); };
    const glm::dvec2 la = local(a), lb = local(b), lc = local(c);
    const double rho = std::sqrt(rho2);
    // The disc's bounding square misses the triangle's box: nothing to add.
    const glm::dvec2 lo = glm::min(la, glm::min(lb, lc)), hi = glm::max(la, glm::max(lb, lc));
    if (lo.x >= rho || lo.y >= rho || hi.x <= -rho || hi.y <= -rho) return 0;
    return std::abs(detail::disc_wedge_area(la.x, la.y, lb.x, lb.y, rho) + detail::disc_wedge_area(lb.x, lb.y, lc.x, lc.y, rho) +
                    detail::disc_wedge_area(lc.x, lc.y, la.x, la.y, rho));
}

/// The triangles of every surface group, for the area of a point's group inside a sphere.
template <Scalar T>
class SurfaceAreas {
public:
    SurfaceAreas() = default;
    /// The groups of `triangles` (kept by reference: they must outlive this) across edges of
    /// dihedral angle below alpha radians (surface_groups).
    SurfaceAreas(std::span<const TriangleVertices<T>> triangles, T alpha) : triangles_(triangles) {
        const SurfaceGroups g = surface_groups(triangles, alpha);
        group_of_ = g.group_of;
        fill_buckets(
            g.count,
            [&](auto emit) {
                for (std::size_t i = 0; i < group_of_.size(); ++i) emit(i, group_of_[i]);
            },
            start_, members_);
    }

    /// Groups of more triangles than this (a curved, finely tessellated surface) count as
    /// covering the whole disc in disc_share(): summing their triangles per point and pass would
    /// cost the group's size (measured in docs/photons.md); the correction is for walls and
    /// boxes, where a disc reaches past an edge or a corner.
    static constexpr std::uint32_t max_group_triangles = 64;

    /// The share of the disc pi r^2 that the surface group of `triangle` covers inside the
    /// sphere about x of radius r: area() / (pi r^2), or 1 for a group of more than
    /// max_group_triangles triangles (the plain estimate's whole disc).
    double disc_share(std::uint32_t triangle, const Vec3<T>& x, double r) const {
        const std::uint32_t k = group_of_[triangle];
        if (start_[k + 1] - start_[k] > max_group_triangles) return 1.0;
        return area(triangle, x, r) / (pi<double> * r * r);
    }

    /// Area of the surface group of triangle `triangle` inside the sphere about x of radius r
    /// (work: the group's triangles).
    double area(std::uint32_t triangle, const Vec3<T>& x, double r) const {
        const std::uint32_t k = group_of_[triangle];
        double sum = 0;
        for (std::uint32_t i = start_[k]; i < start_[k + 1]; ++i) sum += sphere_triangle_area(triangles_[members_[i]], x, r);
        return sum;
    }

private:
    std::span<const TriangleVertices<T>> triangles_;
    std::vector<std::uint32_t> group_of_, start_, members_;
};

}  // namespace glint
