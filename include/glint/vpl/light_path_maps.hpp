// glint/vpl/light_path_maps.hpp: precomputed light path maps (Szécsi 2009, ch. 8)
// for diffuse scenes: the indirect illumination caused by any small light, moved
// or recoloured at run time, from one visibility test per entry point and a weighted sum.
//
// Preprocessing (Szécsi 2009, §§8.1.3-8.2): E entry points z1 are sampled uniformly on the
// surface area (a side of a Lambertian triangle, chosen with probability 1/2: density
// p(z1) = 1 / (2 A)); each receives unit irradiance, i.e. the VPL power 2 A / E, and starts
// a path tree of `branches` walks (shooting.hpp's shoot_path_tree, roulette and BRDF
// sampling as in the VPL method). The VPLs of entry point k illuminate the reference points
// x; the sum of their irradiances at x is the LPM item S^(k)(x) (eq. 8.3):
//   S^(k)(x) = sum_{vpl of k} dPhi (kd_y / pi) cos(theta_x) cos(theta_y) / |x - y|^2 V(x, y).
// Run time (eq. 8.4; the extraction split the fraction; repaired for glint's point light of
// intensity I = Phi_e / 4 pi): the irradiance of entry point k is
//   E_k = I nu(z0, z1^(k)) cos(theta'_{z1^(k)}) / |z0 - z1^(k)|^2
// (nu: visibility by one shadow ray), and the indirect radiance of a diffuse reference point
// is kd(x) / pi sum_k E_k S^(k)(x). Area lights: E_k is estimated from light samples
// (EmitterSet::sample_point, the same shadow-ray test per sample), in place of Szécsi 2009's
// point-to-disc form-factor approximation.
// Reference points (glint has no texture atlas): stratified surface points, the vertices of
// every triangle's subdivision into g x g sub-triangles ((g + 1) (g + 2) / 2 per triangle);
// a pixel interpolates the irradiance of the three points of the sub-triangle containing its
// hit by its barycentrics there (linear per sub-triangle, continuous inside a triangle: the
// "linear interpolation between the reference points" of Szécsi 2009, §8.1.2, which the
// dissertation gets from texture filtering). By default the lattice is shrunk by 10 % toward
// each triangle's centroid (LightPathMapOptions::inset: no point on an edge, linear
// extrapolation between the lattice and the edges; docs/vpl.md compares the error of both).
// A reference point is shaded on the side of its triangle that faces the scene camera's eye
// (glint's LPM is two-sided only through that choice).
// Glossy materials are shaded with their diffuse part kd / pi (Szécsi 2009's light path maps
// are for diffuse scenes); entry points and the paths' vertices follow shooting.hpp.
// Clustering (Szécsi 2009, §8.2.1): entry points are grouped by k-means on their position and
// normal; a cluster's pane is the sum of its members' items and its run-time weight is the
// mean of its members' irradiances.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <atomic>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/parallel.hpp>
#include <glint/core/random.hpp>
#include <glint/vpl/gather.hpp>
#include <glint/vpl/shooting.hpp>

namespace glint {

/// Reference points: the lattice of every triangle's g x g subdivision, the points with
/// barycentrics (i / g, j / g), i, j >= 0, i + j <= g ((g + 1) (g + 2) / 2 per triangle, in
/// triangle order; points on an edge are repeated in each triangle that has it). A value
/// recorded at the points is read back linearly interpolated inside each sub-triangle.
/// With inset s > 0 the lattice is shrunk by 1 - s toward the triangle's centroid (no point
/// on an edge, where a wall meeting the triangle contributes nothing) and read back with
/// linear extrapolation in the band between the lattice and the edges.
template <Scalar T>
struct ReferenceGrid {
    int g = 4;  ///< Subdivisions per triangle edge, in [1, 256].
    T inset = 0;  ///< Fraction s in [0, 0.5] the lattice is shrunk by toward each centroid (0: on the edges).
    std::vector<Vec3<T>> x;          ///< positions, world space, per_triangle() per triangle in triangle order
    std::vector<std::uint32_t> tri;  ///< triangle of each point

    /// The lattice's points and the interpolation weights of one surface point.
    struct Stencil {
        std::size_t index[3];  ///< Indices of the three lattice points (into x).
        T weight[3];  ///< Their weights, summing to 1 (some negative when extrapolating).
    };

    /// The lattice of every triangle of `s` at `grid` subdivisions, shrunk by `shrink`. Throws
    /// Error for grid outside [1, 256] or shrink outside [0, 0.5]. Allocates.
    ReferenceGrid(const Scene<T>& s, int grid, T shrink = T(0)) : g(grid), inset(shrink) {
        if (grid < 1 || grid > 256) throw Error("glint::ReferenceGrid: grid " + std::to_string(grid) + " outside [1, 256]");
        if (!(shrink >= T(0) && shrink <= T(0.5)))
            throw Error("glint::ReferenceGrid: inset " + std::to_string(double(shrink)) + " outside [0, 0.5]");
        const T c = T(1) / T(3);
        for (std::size_t t = 0; t < s.triangles.size(); ++t)
            for (int j = 0; j <= g; ++j)
                for (int i = 0; i + j <= g; ++i) {
                    const T u = c + (T(i) / T(g) - c) * (T(1) - inset), v = c + (T(j) / T(g) - c) * (T(1) - inset);
                    const auto& p = s.triangles[t];
                    x.push_back(p[0] * (T(1) - u - v) + p[1] * u + p[2] * v);
                    tri.push_back(std::uint32_t(t));
                }
    }
    /// Lattice points per triangle, (g + 1) (g + 2) / 2.
    std::size_t per_triangle() const { return std::size_t((g + 1) * (g + 2) / 2); }
    /// Index of lattice point (i, j) of triangle t: rows of constant j, g + 1 - j points each.
    std::size_t index(std::uint32_t t, int i, int j) const {
        return std::size_t(t) * per_triangle() + std::size_t(j * (g + 1) - j * (j - 1) / 2 + i);
    }
    /// The three lattice points of the sub-triangle containing barycentrics (u, v) of
    /// triangle t and the point's barycentrics in it: cell (i, j) is split by its diagonal
    /// into a lower sub-triangle (i, j), (i + 1, j), (i, j + 1) and, when i + j < g - 1, an
    /// upper one (i + 1, j + 1), (i, j + 1), (i + 1, j). (u, v) outside the triangle are
    /// first clamped onto it; with an inset, a point outside the shrunk lattice takes the
    /// nearest cell's sub-triangle and weights that extrapolate (some negative).
    Stencil stencil(std::uint32_t t, T u, T v) const {
        u = std::clamp(u, T(0), T(1)), v = std::clamp(v, T(0), T(1));
        if (u + v > T(1)) u /= u + v, v = T(1) - u;
        const T c = T(1) / T(3), k = T(1) / (T(1) - inset);
        const T a = (c + (u - c) * k) * T(g), b = (c + (v - c) * k) * T(g);  // lattice coordinates
        const int j = std::clamp(int(std::floor(b)), 0, g - 1), i = std::clamp(int(std::floor(a)), 0, g - 1 - j);
        const T fa = a - T(i), fb = b - T(j);
        if (fa + fb > T(1) && i + j < g - 1)
            return {{index(t, i + 1, j + 1), index(t, i, j + 1), index(t, i + 1, j)}, {fa + fb - T(1), T(1) - fa, T(1) - fb}};
        return {{index(t, i, j), index(t, i + 1, j), index(t, i, j + 1)}, {T(1) - fa - fb, fa, fb}};
    }
    /// Values recorded at the points, interpolated linearly at (u, v) of triangle t.
    Rgb<T> interpolate(std::span<const Rgb<T>> values, std::uint32_t t, T u, T v) const {
        const Stencil st = stencil(t, u, v);
        Rgb<T> out(T(0));
        for (int k = 0; k < 3; ++k) out += values[st.index[k]] * st.weight[k];
        return out;
    }
    /// Number of reference points, per_triangle() times the triangle count.
    std::size_t size() const { return x.size(); }
};

/// Settings of build_light_path_map.
struct LightPathMapOptions {
    std::size_t entry_points = 256;  ///< Entry points E sampled on the Lambertian surface (> 0).
    int branches = 4;          ///< walks per entry point (the splitting factor N_s of Szécsi 2009, §8.1.4; >= 1)
    int grid = 4;              ///< reference grid per triangle (g x g sub-triangles, g in [1, 256])
    double inset = 0.1;        ///< the grid's lattice shrunk by 1 - inset toward each centroid (0: on the edges; docs/vpl.md)
    std::size_t clusters = 0;  ///< k-means clusters of entry points; 0 (or >= entry_points): no clustering
    double min_distance = 0;   ///< geometry-term clamp of the gathering, world units (0: unclamped)
    int threads = 0;           ///< Threads gathering the panes (0: hardware concurrency).
    std::uint64_t seed = 1;    ///< Seed of the entry points and their path trees.
    ShootingOptions shooting{};  ///< Walk depth cap of the path trees (its max_depth only).
};

/// A point where a light path map's light paths start: a sampled side of a Lambertian triangle.
template <Scalar T>
struct EntryPoint {
    /// Position z_1, world space.
    Vec3<T> x{0}, n{0};  ///< Unit normal of the sampled side.
    std::uint32_t triangle = 0;  ///< Index of the scene triangle holding x.
};

/// A light path map: reference points, entry points (and clusters), and one pane of items
/// per entry point or cluster (RGB irradiance per reference point for unit irradiance).
template <Scalar T>
struct LightPathMap {
    ReferenceGrid<T> grid;  ///< The reference points the items are recorded at.
    std::vector<EntryPoint<T>> entries;  ///< The entry points, in sampling order.
    std::vector<std::uint32_t> cluster_of;  ///< per entry point: its pane
    std::vector<std::vector<Rgb<T>>> panes;  ///< per pane: the items S(x) of every reference point (grid order)
    std::vector<Vec3<T>> ref_normal;        ///< per reference point: the normal of the side facing the scene camera's eye

    /// Memory of the panes and entry points in bytes (the grid and ref_normal not counted).
    std::size_t bytes() const {
        return panes.size() * grid.size() * sizeof(Rgb<T>) + entries.size() * sizeof(EntryPoint<T>);
    }
};

/// Samples E entry points uniformly on the Lambertian, non-emitting surface (side 1/2 each).
template <Scalar T>
std::vector<EntryPoint<T>> sample_entry_points(const Scene<T>& s, std::size_t n, Pcg32& rng, T& area) {
    std::vector<T> cdf;
    area = 0;
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
        const Material<T>& m = s.materials[s.material_of[t]];
        const auto& v = s.triangles[t];
        if (m.kind == MaterialKind::lambertian && !m.emissive()) area += triangle_area(v[0], v[1], v[2]);
        cdf.push_back(area);
    }
    if (!(area > T(0))) throw Error("glint::sample_entry_points: scene '" + s.name + "' has no Lambertian surface");
    std::vector<EntryPoint<T>> out;
    for (std::size_t k = 0; k < n; ++k) {
        const auto it = std::upper_bound(cdf.begin(), cdf.end(), rng.uniform<T>() * area);
        const std::size_t t = std::min<std::size_t>(std::size_t(it - cdf.begin()), cdf.size() - 1);
        const auto& v = s.triangles[t];
        const Vec3<T> x = sample_triangle(v[0], v[1], v[2], Vec2<T>(rng.uniform<T>(), rng.uniform<T>()));
        out.push_back({x, rng.uniform<T>() < T(0.5) ? s.normal(t) : -s.normal(t), std::uint32_t(t)});
    }
    return out;
}

/// k-means (Lloyd, 12 iterations) on entry points' positions and normals (a normal counts
/// as `normal_weight` of distance); returns each entry point's cluster.
template <Scalar T>
std::vector<std::uint32_t> cluster_entry_points(std::span<const EntryPoint<T>> e, std::size_t k, T normal_weight) {
    std::vector<std::uint32_t> of(e.size(), 0);
    if (k == 0 || k >= e.size()) {
        for (std::size_t i = 0; i < e.size(); ++i) of[i] = std::uint32_t(i);
        return of;
    }
    std::vector<Vec3<T>> cx(k), cn(k);
    for (std::size_t c = 0; c < k; ++c) cx[c] = e[c * e.size() / k].x, cn[c] = e[c * e.size() / k].n;
    for (int it = 0; it < 12; ++it) {
        for (std::size_t i = 0; i < e.size(); ++i) {
            T best = std::numeric_limits<T>::max();
            for (std::size_t c = 0; c < k; ++c) {
                const Vec3<T> dx = e[i].x - cx[c], dn = (e[i].n - cn[c]) * normal_weight;
                const T d = glm::dot(dx, dx) + glm::dot(dn, dn);
                if (d < best) best = d, of[i] = std::uint32_t(c);
            }
        }
        std::vector<Vec3<T>> sx(k, Vec3<T>(0)), sn(k, Vec3<T>(0));
        std::vector<std::size_t> count(k, 0);
        for (std::size_t i = 0; i < e.size(); ++i) sx[of[i]] += e[i].x, sn[of[i]] += e[i].n, ++count[of[i]];
        for (std::size_t c = 0; c < k; ++c)
            if (count[c]) cx[c] = sx[c] / T(count[c]), cn[c] = sn[c] / T(count[c]);
    }
    return of;
}

/// The items of every reference point: for each entry point k, the irradiance its path
/// tree's VPLs give the point, added to k's pane. Blocks of 64 points in parallel.
template <Scalar T, class V>
    requires VisibilityPolicy<V, T>
void gather_panes(const Scene<T>& s, const std::vector<std::vector<Vpl<T>>>& trees, const V& visibility,
                  const LightPathMapOptions& opt, LightPathMap<T>& map) {
    const T d2min = T(opt.min_distance * opt.min_distance);
    const std::size_t n = map.grid.size();
    map.ref_normal.resize(n);
    for (std::size_t r = 0; r < n; ++r) {
        const Vec3<T> ng = s.normal(map.grid.tri[r]);
        map.ref_normal[r] = glm::dot(ng, s.camera.eye - map.grid.x[r]) >= T(0) ? ng : -ng;
    }
    const int blocks = int((n + 63) / 64);
    detail::parallel_blocks(blocks, opt.threads, [&](std::atomic<int>& next) {
        V vis = visibility;
        const auto unit = [](const Vec3<T>&) { return Rgb<T>(T(1)); };
        for (int b = next++; b < blocks; b = next++)
            for (std::size_t r = std::size_t(b) * 64; r < std::min(n, std::size_t(b + 1) * 64); ++r) {
                vis.set_point(map.grid.x[r], map.ref_normal[r]);
                for (std::size_t k = 0; k < trees.size(); ++k)
                    map.panes[map.cluster_of[k]][r] +=
                        vpl_sum(map.grid.x[r], map.ref_normal[r], std::span<const Vpl<T>>(trees[k]), vis, d2min, unit);
            }
    });
}

/// Preprocessing: entry points, their path trees, and the items at every reference point
/// (visibility policy V, one copy per thread).
template <RayAccelerator A, class R, class V, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T> && VisibilityPolicy<V, T>
LightPathMap<T> build_light_path_map(const Scene<T>& s, const A& accel, const R& roulette, const V& visibility,
                                     const LightPathMapOptions& opt) {
    if (opt.entry_points == 0 || opt.branches < 1)
        throw Error("glint::build_light_path_map: entry_points " + std::to_string(opt.entry_points) + " and branches " +
                    std::to_string(opt.branches) + " must be positive");
    LightPathMap<T> map{ReferenceGrid<T>(s, opt.grid, T(opt.inset)), {}, {}, {}, {}};
    Pcg32 rng(opt.seed, 0x19a7);
    T area = 0;
    map.entries = sample_entry_points(s, opt.entry_points, rng, area);
    const Rgb<T> power(T(2) * area / T(opt.entry_points));  // unit irradiance over 1 / p(z1) / E
    std::vector<std::vector<Vpl<T>>> trees(map.entries.size());
    for (std::size_t k = 0; k < map.entries.size(); ++k) {
        const EntryPoint<T>& e = map.entries[k];
        Pcg32 walk = Pcg32::hashed(opt.seed, 0x1000000 + k);
        shoot_path_tree(s, accel, roulette, e.x, e.n, s.materials[s.material_of[e.triangle]], power, opt.branches, walk,
                        opt.shooting.max_depth, trees[k]);
    }
    map.cluster_of = cluster_entry_points(std::span<const EntryPoint<T>>(map.entries), opt.clusters, T(0.5));
    const std::size_t panes = 1 + *std::max_element(map.cluster_of.begin(), map.cluster_of.end());
    map.panes.assign(panes, std::vector<Rgb<T>>(map.grid.size(), Rgb<T>(T(0))));
    gather_panes(s, trees, visibility, opt, map);
    return map;
}

/// Run time: the irradiance E_k of every entry point from the lights of `lit` (same
/// geometry), `samples` light samples each with one shadow ray (exact for one point light).
template <RayAccelerator A, Scalar T = typename A::scalar_type>
std::vector<Rgb<T>> entry_irradiance(const LightPathMap<T>& map, const Scene<T>& lit, const A& accel, int samples,
                                     std::uint64_t seed) {
    const EmitterSet<T> lights(lit);
    std::vector<Rgb<T>> out(map.entries.size(), Rgb<T>(T(0)));
    Pcg32 rng(seed, 0xe17);
    for (std::size_t k = 0; k < map.entries.size(); ++k) {
        const EntryPoint<T>& e = map.entries[k];
        for (int i = 0; i < samples; ++i) {
            T pdf;
            const T u = rng.uniform<T>();
            const LightSample<T> ls = lights.sample_point(u, Vec2<T>(rng.uniform<T>(), rng.uniform<T>()), pdf);
            const Vec3<T> d = ls.position - e.x;
            const T r2 = glm::dot(d, d), c1 = glm::dot(e.n, d) / std::sqrt(r2);
            const T cl = ls.normal == Vec3<T>(0) ? T(1) : -glm::dot(ls.normal, d) / std::sqrt(r2);
            if (!(c1 > T(0)) || !(cl > T(0)) || !(pdf > T(0))) continue;
            const Ray<T> r0 = detail::light_spawn(e.x, e.n, d);
            if (accel.any_hit(Ray<T>{r0.origin, ls.position - r0.origin, T(0), T(1) - T(1e-4)})) continue;
            out[k] += ls.towards(-d / std::sqrt(r2)) * (c1 * cl / (r2 * pdf * T(samples)));
        }
    }
    return out;
}

/// Indirect irradiance of every reference point (eq. 8.4): sum over panes of the pane's
/// weight (its members' mean irradiance) times its items.
template <Scalar T>
std::vector<Rgb<T>> reference_irradiance(const LightPathMap<T>& map, std::span<const Rgb<T>> entry_e) {
    std::vector<Rgb<T>> w(map.panes.size(), Rgb<T>(T(0)));
    std::vector<T> count(map.panes.size(), T(0));
    for (std::size_t k = 0; k < entry_e.size(); ++k) w[map.cluster_of[k]] += entry_e[k], count[map.cluster_of[k]] += T(1);
    std::vector<Rgb<T>> out(map.grid.size(), Rgb<T>(T(0)));
    for (std::size_t c = 0; c < map.panes.size(); ++c) {
        if (!(w[c].max() > T(0))) continue;  // an unlit pane costs nothing
        const Rgb<T> wc = w[c] / count[c];
        for (std::size_t r = 0; r < out.size(); ++r) out[r] += wc * map.panes[c][r];
    }
    return out;
}

/// Indirect radiance per pixel point: kd / pi times the reference irradiance interpolated
/// at the point's barycentrics (times the camera path's weight).
template <Scalar T>
std::vector<Rgb<T>> light_path_map_image(const LightPathMap<T>& map, const Scene<T>& s, std::span<const PixelPoint<T>> points,
                                         std::span<const Rgb<T>> ref_e) {
    std::vector<Rgb<T>> out(points.size(), Rgb<T>(T(0)));
    for (std::size_t i = 0; i < points.size(); ++i) {
        const PixelPoint<T>& p = points[i];
        if (!p.hit) continue;
        const Rgb<T> kd = s.materials[p.material].kd;
        out[i] = p.weight * kd * map.grid.interpolate(ref_e, p.triangle, p.u, p.v) / pi<T>;
    }
    return out;
}

}  // namespace glint
