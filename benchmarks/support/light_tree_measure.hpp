// benchmarks/support/light_tree_measure.hpp: what bench_lights' --tree-scaling and
// --pick-timing modes measure of the stochastic light tree (lights/light_tree.hpp), single
// thread.
//
//   random_point_lights(n, seed)   n point lights in a 100 m cube, a third each isotropic, spot
//                                  and oriented (cosine), random axes, intensities 0.1 .. 10
//   tree_scaling(n, seed)          the tree's build time (median of reps), bytes per light and
//                                  nanoseconds per pick at random shading points in the cube
//   pick_timing(scene, seed)       nanoseconds per pick and per probability() at points
//                                  uniform on the scene's triangles (area-weighted), with their
//                                  normals: the descent's cost on a real scene
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glint/core/random.hpp>
#include <glint/lights/light_bounds.hpp>
#include <glint/lights/light_tree.hpp>
#include <glint/tracer/scene.hpp>

#include "clock.hpp"

namespace glint::bench {

inline Vec3<float> random_unit(Pcg32& rng) {
    const float z = 1 - 2 * rng.uniform<float>(), phi = 2 * pi<float> * rng.uniform<float>();
    const float s = std::sqrt(std::max(0.0f, 1 - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
}

inline std::vector<PointLight<float>> random_point_lights(std::size_t n, std::uint64_t seed) {
    Pcg32 rng(seed);
    std::vector<PointLight<float>> out;
    out.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3<float> p(100 * rng.uniform<float>(), 100 * rng.uniform<float>(), 100 * rng.uniform<float>());
        const Rgb<float> I(0.1f + 9.9f * rng.uniform<float>());
        const Vec3<float> axis = random_unit(rng);
        if (i % 3 == 0) out.push_back(PointLight<float>::isotropic(p, I));
        else if (i % 3 == 1) out.push_back(PointLight<float>::spot(p, axis, I, 0.6f, 0.4f));
        else out.push_back(PointLight<float>::oriented(p, axis, I));
    }
    return out;
}

/// Shading points: uniform in the cube with random normals, or uniform on a scene's triangles.
struct ShadingPoints {
    std::vector<Vec3<float>> x, n;
};

inline ShadingPoints cube_points(std::size_t count, std::uint64_t seed) {
    Pcg32 rng(seed);
    ShadingPoints s;
    for (std::size_t i = 0; i < count; ++i) {
        s.x.emplace_back(100 * rng.uniform<float>(), 100 * rng.uniform<float>(), 100 * rng.uniform<float>());
        s.n.push_back(random_unit(rng));
    }
    return s;
}

inline ShadingPoints surface_points(const Scene<float>& scene, std::size_t count, std::uint64_t seed) {
    std::vector<double> cdf;
    double total = 0;
    for (const auto& t : scene.triangles) cdf.push_back(total += 0.5 * glm::length(glm::cross(t[1] - t[0], t[2] - t[0])));
    Pcg32 rng(seed);
    ShadingPoints s;
    for (std::size_t i = 0; i < count; ++i) {
        const auto k = std::size_t(std::lower_bound(cdf.begin(), cdf.end(), rng.uniform<double>() * total) - cdf.begin());
        const auto& t = scene.triangles[std::min(k, cdf.size() - 1)];
        float a = rng.uniform<float>(), b = rng.uniform<float>();
        if (a + b > 1) a = 1 - a, b = 1 - b;
        s.x.push_back(t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b);
        s.n.push_back(safe_normalize(glm::cross(t[1] - t[0], t[2] - t[0])));
    }
    return s;
}

struct PickTiming {
    double pick_ns = 0, probability_ns = 0;
    double checksum = 0;  // keeps the work from being optimized away
};

/// Nanoseconds per pick and per probability() of `tree` over the points (best of `reps`).
inline PickTiming pick_timing(const LightTree<float>& tree, const ShadingPoints& pts, int reps = 3) {
    PickTiming r{1e30, 1e30, 0};
    std::vector<std::size_t> picked(pts.x.size());
    for (int rep = 0; rep < reps; ++rep) {
        auto t0 = std::chrono::steady_clock::now();
        double sum = 0;
        for (std::size_t i = 0; i < pts.x.size(); ++i) {
            const auto p = tree.pick(pts.x[i], pts.n[i], float(i) * 0.6180339f - float(std::size_t(float(i) * 0.6180339f)));
            picked[i] = p.index;
            sum += p.probability;
        }
        r.pick_ns = std::min(r.pick_ns, 1e9 * seconds_since(t0) / double(pts.x.size()));
        t0 = std::chrono::steady_clock::now();
        for (std::size_t i = 0; i < pts.x.size(); ++i) sum += tree.probability(pts.x[i], pts.n[i], picked[i]);
        r.probability_ns = std::min(r.probability_ns, 1e9 * seconds_since(t0) / double(pts.x.size()));
        r.checksum += sum;
    }
    return r;
}

struct TreeScaling {
    std::size_t lights = 0;
    double build_seconds = 0, bytes_per_light = 0, pick_ns = 0;
};

inline TreeScaling tree_scaling(std::size_t n, std::uint64_t seed, int reps = 3) {
    const auto lights = random_point_lights(n, seed);
    std::vector<LightBounds<float>> bounds;
    for (const auto& l : lights) bounds.push_back(light_bounds(l));
    TreeScaling r{n, 1e30, 0, 0};
    LightTree<float> tree;
    for (int rep = 0; rep < reps; ++rep) {
        const auto t0 = std::chrono::steady_clock::now();
        tree = LightTree<float>(bounds);
        r.build_seconds = std::min(r.build_seconds, seconds_since(t0));
    }
    r.bytes_per_light = double(tree.bytes()) / double(n);
    r.pick_ns = pick_timing(tree, cube_points(100000, seed + 1), reps).pick_ns;
    return r;
}

}  // namespace glint::bench
