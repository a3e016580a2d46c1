// benchmarks/support/lie_measure.hpp: direct illumination through local illumination
// environments (lights/lie_direct.hpp) against the standard ray tracer (every light a shadow
// ray through glint's 8-wide BVH) on one scene: what bench_lights' LIE rows measure.
//
// Every pixel: one camera ray through its centre and the direct light of the scene's point
// lights at the hit (area lights as points on them). Methods, timed alternately (rep r runs them
// in rotated order; the best time of each is kept), single thread: "standard", "lie" and
// "lie-mask", and "no-shadows" (primary rays and light evaluation only). error_E is Fernandez 2004's eq. 4.3, the mean over pixels of
// min(|L_LIE - L| / L, 1) on luminance, against the standard ray tracer's exact L (a pixel with
// L = 0 counts 0 if L_LIE = 0, else 1); rmse is the root mean square of L_LIE - L over pixels.
// The LIE's construction (its own row, method "lie-build") is not in the rendering times.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glint/lights/lie_direct.hpp>
#include <glint/trees/mesh_bvh.hpp>

namespace glint::bench {

struct LieRow {
    std::string scene, method;
    std::size_t lights = 0;
    double lights_per_pixel = 0, shadow_rays_per_pixel = 0, seconds = 0, error_E = 0, rmse = 0;
    double blocker_tests_per_pixel = 0;  // ray-triangle tests against blocker lists (not a CSV column)
};

struct LieMeasureOptions {
    int width = 256, height = 256, reps = 3;
    LieSettings lie{};
};

namespace detail {
struct LieImage {
    std::vector<float> L;  // luminance per pixel
    double lights = 0, rays = 0, tests = 0, seconds = 0;
};

/// Every light evaluated without a visibility test: the floor no visibility method goes below.
inline LieDirect<float>::Shaded unshadowed(const LieDirect<float>& d, const ShadingPoint<float>& sp) {
    LieDirect<float>::Shaded out;
    for (const auto& l : d.lie().lights()) {
        Rgb<float> f;
        if (!lie_unshadowed(sp, l, f)) continue;
        ++out.cost.lights;
        out.L += f;
    }
    return out;
}

/// One pass over the image with method m (0: standard, 1: lie, 2: lie-mask, 3: no shadows).
template <class Accel>
LieImage lie_pass(const Scene<float>& scene, const Accel& accel, const LieDirect<float>& plain,
                  const LieDirect<float>& masked, int m, int w, int h) {
    LieImage out;
    out.L.assign(std::size_t(w) * std::size_t(h), 0.0f);
    const auto start = std::chrono::steady_clock::now();
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Ray<float> ray = scene.camera.ray((float(x) + 0.5f) / float(w), (float(y) + 0.5f) / float(h), float(w) / float(h));
            std::optional<SurfaceBrdf<float>> brdf;
            ShadingPoint<float> sp;
            if (!lie_camera_point(scene, accel, ray, brdf, sp)) continue;
            RayQueries<Accel> q(accel);
            const auto s = m == 3 ? unshadowed(plain, sp) : m == 0 ? plain.shadow_rays(sp, q) : (m == 1 ? plain : masked).shade(sp, q);
            out.L[std::size_t(y) * std::size_t(w) + std::size_t(x)] = s.L.luminance();
            out.rays += s.cost.accel_rays + s.cost.blocker_rays;
            out.lights += s.cost.lights;
            out.tests += s.cost.blocker_tests;
        }
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}
}  // namespace detail

/// The rows "lie-build", "standard", "lie", "lie-mask" and "no-shadows" (every light counted
/// visible, no ray: the floor of any visibility method, and its error) for `scene` (its point lights and area lights).
inline std::vector<LieRow> measure_lie(const Scene<float>& scene, LieMeasureOptions o) {
    using Accel = MeshBvh<MollerTrumbore<float>, 8>;
    const Accel accel(std::span<const TriangleVertices<float>>(scene.triangles));
    o.lie.aspect = double(o.width) / double(o.height);
    o.lie.threads = 1;
    const auto t0 = std::chrono::steady_clock::now();
    const LieDirect<float> plain(scene, accel, o.lie, false);
    const double build = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const LieDirect<float> masked = plain.with_masking(true);
    std::vector<detail::LieImage> best(4);
    for (int r = 0; r < std::max(o.reps, 1); ++r)
        for (int k = 0; k < 4; ++k) {
            const int m = (k + r) % 4;
            auto img = detail::lie_pass(scene, accel, plain, masked, m, o.width, o.height);
            if (r == 0 || img.seconds < best[std::size_t(m)].seconds) best[std::size_t(m)] = std::move(img);
        }
    const double px = double(o.width) * double(o.height);
    const std::size_t nl = plain.lie().lights().size();
    std::vector<LieRow> rows{{scene.name, "lie-build", nl, 0, 0, build, 0, 0, 0}};
    const char* names[4] = {"standard", "lie", "lie-mask", "no-shadows"};
    for (int m = 0; m < 4; ++m) {
        const auto& img = best[std::size_t(m)];
        double e = 0, se = 0;
        for (std::size_t i = 0; i < img.L.size(); ++i) {
            const double ref = best[0].L[i], d = std::abs(double(img.L[i]) - ref);
            e += ref > 0 ? std::min(d / ref, 1.0) : (d > 0 ? 1.0 : 0.0);
            se += d * d;
        }
        rows.push_back({scene.name, names[m], nl, img.lights / px, img.rays / px, img.seconds, e / px, std::sqrt(se / px),
                        img.tests / px});
    }
    return rows;
}

}  // namespace glint::bench
