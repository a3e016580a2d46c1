// tests/support/tree_scenes.hpp: generated test scenes and ray sets for the trees' tests and
// benchmarks (a fixture, not part of the library and not installed; tests, benchmarks and
// examples find it through glint_build's include path): a tessellated sphere, a torus knot
// (Szécsi 2009, §5 uses one of 2880 triangles), a random triangle soup, "teapot in a stadium"
// (Szécsi 2009, §4.2: a huge ground plane with a small dense object), a flat grid;
// primary camera rays and incoherent diffuse rays leaving surface points on both sides.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

template <class T>
using Mesh = std::vector<TriangleVertices<T>>;

namespace detail {

/// Triangulates a (rows x cols) grid of points, periodic in the directions asked for.
template <class T, class F>
void add_grid(Mesh<T>& m, int rows, int cols, bool wrap_rows, bool wrap_cols, F&& point) {
    const int r_end = wrap_rows ? rows : rows - 1, c_end = wrap_cols ? cols : cols - 1;
    for (int i = 0; i < r_end; ++i)
        for (int j = 0; j < c_end; ++j) {
            const Vec3<T> a = point(i, j), b = point((i + 1) % rows, j);
            const Vec3<T> c = point((i + 1) % rows, (j + 1) % cols), d = point(i, (j + 1) % cols);
            m.push_back({a, b, c});
            m.push_back({a, c, d});
        }
}

}  // namespace detail

/// UV sphere: 2 * stacks * slices triangles (the pole rows are degenerate, zero-area
/// triangles on purpose: trees must cope with them).
template <Scalar T>
Mesh<T> make_sphere(int stacks, int slices, Vec3<T> centre = Vec3<T>(0), T radius = T(1)) {
    Mesh<T> m;
    detail::add_grid<T>(m, stacks + 1, slices, false, true, [&](int i, int j) {
        const double th = pi<double> * i / stacks, ph = 2 * pi<double> * j / slices;
        return centre + radius * Vec3<T>(Vec3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    });
    return m;
}

/// (p, q) torus knot as a tube: 2 * segments * sides triangles; segments = 120, sides = 12
/// gives Szécsi 2009, §5's 2880 triangles.
template <Scalar T>
Mesh<T> make_torus_knot(int segments = 120, int sides = 12, int p = 2, int q = 3, T tube = T(0.25)) {
    auto curve = [&](double s) {
        const double r = 2.0 + std::cos(q * s);
        return Vec3d(r * std::cos(p * s), r * std::sin(p * s), -std::sin(q * s));
    };
    Mesh<T> m;
    detail::add_grid<T>(m, segments, sides, true, true, [&](int i, int j) {
        const double s = 2 * pi<double> * i / segments, ds = 1e-4;
        const Vec3d c = curve(s);
        const Vec3d tan = glm::normalize(curve(s + ds) - curve(s - ds));
        Vec3d b1, b2;
        orthonormal_basis(tan, b1, b2);
        const double a = 2 * pi<double> * j / sides;
        return Vec3<T>(c + double(tube) * (std::cos(a) * b1 + std::sin(a) * b2));
    });
    return m;
}

/// n random triangles with vertices in the unit cube, edges up to `size`.
template <Scalar T>
Mesh<T> make_soup(std::size_t n, std::uint64_t seed = 1, T size = T(0.1)) {
    Pcg32 rng(seed);
    auto u = [&] { return rng.uniform<T>(); };
    Mesh<T> m(n);
    for (auto& t : m) {
        const Vec3<T> c(u(), u(), u());
        for (auto& v : t) v = c + size * (Vec3<T>(u(), u(), u()) - T(0.5));
    }
    return m;
}

/// "Teapot in a stadium": a ground plane of half-size `ground` (tessellated into 2 * g^2
/// triangles) with a small dense torus knot (about unit size) standing on it at the origin.
template <Scalar T>
Mesh<T> make_teapot_in_stadium(T ground = T(1000), int g = 4, int segments = 120, int sides = 12) {
    Mesh<T> m = make_torus_knot<T>(segments, sides);
    for (auto& t : m)
        for (auto& v : t) v = v * T(0.25) + Vec3<T>(0, 0, T(1));
    detail::add_grid<T>(m, g + 1, g + 1, false, false, [&](int i, int j) {
        return Vec3<T>(ground * (T(2) * T(i) / T(g) - T(1)), ground * (T(2) * T(j) / T(g) - T(1)), T(0));
    });
    return m;
}

/// A flat n x n grid in the plane z = 0 over [0, 1]^2: every triangle is planar in z.
template <Scalar T>
Mesh<T> make_flat_grid(int n) {
    Mesh<T> m;
    detail::add_grid<T>(m, n + 1, n + 1, false, false,
                        [&](int i, int j) { return Vec3<T>(T(i) / T(n), T(j) / T(n), T(0)); });
    return m;
}

template <class T>
AABB<T> mesh_bounds(std::span<const TriangleVertices<T>> m) {
    AABB<T> b;
    for (const auto& t : m)
        for (const auto& v : t) b.extend(v);
    return b;
}

/// Primary rays of a pinhole camera looking at the scene's centre from outside, width x
/// height pixels (row-major), with one jittered sample per pixel.
template <Scalar T>
std::vector<Ray<T>> make_primary_rays(std::span<const TriangleVertices<T>> m, int width, int height,
                                      std::uint64_t seed = 7) {
    const AABB<T> b = mesh_bounds(m);
    const Vec3d c(b.center());
    const double radius = std::max(0.5 * glm::length(Vec3d(b.extent())), 1e-6);
    const Vec3d eye = c + radius * Vec3d(0.9, -1.6, 0.8);
    const Vec3d fwd = glm::normalize(c - eye), right = glm::normalize(glm::cross(fwd, Vec3d(0, 0, 1)));
    const Vec3d up = glm::cross(right, fwd);
    const double fov = std::tan(0.5 * 0.9);  // about 52 degrees
    Pcg32 rng(seed);
    std::vector<Ray<T>> rays;
    rays.reserve(std::size_t(width) * height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const double sx = (2.0 * (x + rng.uniform<double>()) / width - 1.0) * fov;
            const double sy = (1.0 - 2.0 * (y + rng.uniform<double>()) / height) * fov * height / width;
            Ray<T> r;
            r.origin = Vec3<T>(eye);
            r.direction = Vec3<T>(glm::normalize(fwd + sx * right + sy * up));
            rays.push_back(r);
        }
    return rays;
}

/// Incoherent diffuse rays: each leaves a random point of a random triangle (area
/// weighted) on a random side, cosine-distributed about that side's normal, with
/// tmin = 1e-4 of the scene's size so that it does not hit its own triangle.
template <Scalar T>
std::vector<Ray<T>> make_incoherent_rays(std::span<const TriangleVertices<T>> m, std::size_t n,
                                         std::uint64_t seed = 11) {
    std::vector<double> cdf;
    cdf.reserve(m.size());
    double total = 0;
    for (const auto& t : m) {
        total += glm::length(glm::cross(Vec3d(t[1] - t[0]), Vec3d(t[2] - t[0])));
        cdf.push_back(total);
    }
    const AABB<T> b = mesh_bounds(m);
    const T eps = T(1e-4) * std::max(glm::length(b.extent()), T(1e-6));
    Pcg32 rng(seed);
    std::vector<Ray<T>> rays;
    rays.reserve(n);
    while (rays.size() < n && total > 0) {
        const double x = rng.uniform<double>() * total;
        const auto i = std::min<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin(), m.size() - 1);
        const auto& t = m[i];
        double u = rng.uniform<double>(), v = rng.uniform<double>();
        if (u + v > 1) u = 1 - u, v = 1 - v;
        const Vec3d p = Vec3d(t[0]) + u * Vec3d(t[1] - t[0]) + v * Vec3d(t[2] - t[0]);
        Vec3d nrm = safe_normalize(glm::cross(Vec3d(t[1] - t[0]), Vec3d(t[2] - t[0])));
        if (rng.uniform<double>() < 0.5) nrm = -nrm;
        Vec3d b1, b2;
        orthonormal_basis(nrm, b1, b2);
        const double r = std::sqrt(rng.uniform<double>()), phi = 2 * pi<double> * rng.uniform<double>();
        const Vec3d d = r * std::cos(phi) * b1 + r * std::sin(phi) * b2 + std::sqrt(std::max(0.0, 1 - r * r)) * nrm;
        Ray<T> ray;
        ray.origin = Vec3<T>(p);
        ray.direction = Vec3<T>(d);
        ray.tmin = eps;
        rays.push_back(ray);
    }
    return rays;
}

/// Shadow rays from the hit points of `primary` (in its order: coherent where it is) to one
/// point light above the scene (z up, as make_primary_rays' camera): direction light - p,
/// interval (1e-4, 1 - 1e-4); `hit_t(ray, t)` gives a ray's closest hit (false: a miss).
/// At most `max` rays.
template <class HitT>
std::vector<Ray<float>> make_light_shadow_rays(const std::vector<Ray<float>>& primary, const AABB<float>& box,
                                               HitT&& hit_t, std::size_t max = ~std::size_t(0)) {
    const Vec3f light = box.center() + Vec3f(0.1f, 0.2f, 1.0f) * glm::length(box.extent());
    std::vector<Ray<float>> out;
    for (const Ray<float>& r : primary) {
        float t = 0;
        if (out.size() == max) break;
        if (!hit_t(r, t)) continue;
        Ray<float> s;
        s.origin = r.origin + t * r.direction;
        s.direction = light - s.origin;
        s.tmin = 1e-4f;
        s.tmax = 1.0f - 1e-4f;
        out.push_back(s);
    }
    return out;
}

}  // namespace glint
