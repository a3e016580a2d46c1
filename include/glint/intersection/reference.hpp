// glint/intersection/reference.hpp: an extended-precision reference for ray-triangle tests.
//
// Solves o + t d = v0 + u (v1 - v0) + v (v2 - v0) by Cramer's rule in long double (64-bit
// significand on x86) from the exact float or double inputs, and measures how close the ray
// passes to the triangle's boundary in units of the rounding error a test of precision T can
// be expected to make there. Tests and the stress report use it to separate real errors
// (a wrong decision far from any edge) from the unavoidable band of a few ulps at edges.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>

namespace glint {

/// Result of reference_intersect: the exact-as-possible answer and how far it lies from the
/// decision boundaries, in units of precision T's rounding.
struct ReferenceHit {
    bool hit = false;        ///< t in (tmin, tmax) and all barycentrics >= 0.
    bool defined = false;    ///< False for degenerate triangles and rays parallel to the plane.
    /// Ray parameter of the plane hit (valid when `defined`).
    long double t = 0, u = 0, v = 0;  ///< Barycentric weight of vertex 2.
    /// @var u
    /// Barycentric weight of vertex 1.

    /// Distance from the hit point on the plane to the nearest edge line, in units of
    /// eps_T * scale / cos(angle): how many "ulps" a test of precision T could be off by.
    /// Decisions closer than a few units to an edge may legitimately differ between tests.
    double edge_ulps = 0;
    /// The same unit (eps_T * scale / cos) converted to the ray parameter and multiplied by
    /// the triangle's condition number: a test's t is "within k ulps" when
    /// |t - t_ref| <= k * t_unit.
    double t_unit = 0;
};

/// Intersects `r` with triangle (a, b, c) in long double from the exact T inputs; never
/// throws. Reference for tests and the stress report (long double, square roots), not for rendering.
template <class T>
ReferenceHit reference_intersect(const Ray<T>& r, const Vec3<T>& a, const Vec3<T>& b,
                                 const Vec3<T>& c) {
    using L = long double;
    ReferenceHit h;
    const L ox = r.origin.x, oy = r.origin.y, oz = r.origin.z;
    const L dx = r.direction.x, dy = r.direction.y, dz = r.direction.z;
    const L e1x = L(b.x) - a.x, e1y = L(b.y) - a.y, e1z = L(b.z) - a.z;
    const L e2x = L(c.x) - a.x, e2y = L(c.y) - a.y, e2z = L(c.z) - a.z;
    const L sx = ox - a.x, sy = oy - a.y, sz = oz - a.z;
    // n = e1 x e2
    const L nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
    const L det = -(dx * nx + dy * ny + dz * nz);  // = e1 . (d x e2)
    const L nlen = std::sqrt(nx * nx + ny * ny + nz * nz);
    const L dlen = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(nlen > 0) || !(dlen > 0) || det == 0 || !std::isfinite(double(det))) return h;
    // Cramer's rule.
    const L px = dy * e2z - dz * e2y, py = dz * e2x - dx * e2z, pz = dx * e2y - dy * e2x;
    const L qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
    h.u = (sx * px + sy * py + sz * pz) / det;
    h.v = (dx * qx + dy * qy + dz * qz) / det;
    h.t = (e2x * qx + e2y * qy + e2z * qz) / det;
    h.defined = std::isfinite(double(h.t));
    if (!h.defined) return h;
    const L w = 1 - h.u - h.v;
    h.hit = w >= 0 && h.u >= 0 && h.v >= 0 && h.t > L(r.tmin) && h.t < L(r.tmax);
    // Distances to the three edge lines: barycentric times the altitude over that edge.
    const L area2 = nlen;
    auto len = [](L x, L y, L z) { return std::sqrt(x * x + y * y + z * z); };
    const L l0 = len(e2x - e1x, e2y - e1y, e2z - e1z);  // edge opposite v0
    const L dist = std::min({std::abs(w) * area2 / l0, std::abs(h.u) * area2 / len(e2x, e2y, e2z),
                             std::abs(h.v) * area2 / len(e1x, e1y, e1z)});
    L scale = 0;
    for (const auto* p : {&a, &b, &c, &r.origin})
        for (int k = 0; k < 3; ++k) scale = std::max(scale, L(std::abs((*p)[k])));
    for (int k = 0; k < 3; ++k) scale = std::max(scale, std::abs(L(r.origin[k]) + h.t * L(r.direction[k])));
    const L cosine = std::abs(det) / (nlen * dlen);
    const L unit = L(std::numeric_limits<T>::epsilon()) * scale / std::max(cosine, L(1e-6));
    h.edge_ulps = double(dist / unit);
    // An error of one unit in the plane's position along its normal moves the hit by
    // unit * cos / (|d| cos) ... in t: eps * scale / (|d| cos).
    // Rounding the inputs tilts the plane by about eps times the triangle's condition
    // (longest edge / smallest altitude), so t's unit grows with it for slivers.
    const L longest = std::max({l0, len(e1x, e1y, e1z), len(e2x, e2y, e2z)});
    const L condition = longest * longest / area2;
    h.t_unit = double(L(std::numeric_limits<T>::epsilon()) * scale * condition /
                      (dlen * std::max(cosine, L(1e-6))));
    return h;
}

}  // namespace glint
