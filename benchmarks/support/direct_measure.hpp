// benchmarks/support/direct_measure.hpp: many-light direct illumination at the primary hits
// (what Fernandez 2004 measures, ch. 3 and 5), each method against the standard ray tracer on
// the same scene in the same run: bench_lights' "direct" section.
//
// Every pixel: one camera ray through its centre and the direct light of the scene's point
// lights at its diffuse or glossy hit (lie_camera_point). Area lights enter as the oriented
// points the cuts use (points_scene: lights/light_points.hpp's split), so that every method
// computes the same sum over the same points with shadow rays built the same way
// (lie_shadow_ray). A method is a DirectMethod: a name and a function shading one hit and
// counting its cost; the factories below make them (the standard ray tracer: every light with a
// non-zero unoccluded contribution gets a shadow ray through glint's 8-wide BVH; "camera": the
// camera rays alone; "no-shadows": every light evaluated, no ray, the floor of any method that
// evaluates every light; LIE with
// and without masking; dense cuts at a threshold). A method's precomputation (LIE construction,
// the cluster tree) is timed as its own row, "<name>-build", not in the rendering time.
// measure_direct runs the methods alternately (rep r in rotated order; the best time of each
// kept), single thread; error_E is eq. 4.3, the mean over pixels of min(|L - L_std| / L_std, 1)
// on luminance against the standard ray tracer's image (a pixel with L_std = 0 counts 0 if L = 0,
// else 1); rmse over pixels of the luminance difference.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/lights/cluster_tree.hpp>
#include <glint/lights/cuts.hpp>
#include <glint/lights/lie_direct.hpp>
#include <glint/lights/light_points.hpp>
#include <glint/lights/sparse_direct.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "clock.hpp"

namespace glint::bench {

using DirectAccel = MeshBvh<MollerTrumbore<float>, 8>;
using DirectQueries = RayQueries<DirectAccel>;

/// One CSV row: scene,method,lights,lights_per_pixel,shadow_rays_per_pixel,seconds,error_E,rmse.
struct DirectRow {
    std::string scene, method;
    std::size_t lights = 0;
    double lights_per_pixel = 0, shadow_rays_per_pixel = 0, seconds = 0, error_E = 0, rmse = 0;
    double blocker_tests_per_pixel = 0;  // ray-triangle tests against LIE blocker lists (not a CSV column)
};

/// What shading one hit cost: lights evaluated (f G, or a cut's nodes), shadow rays (through
/// the BVH or against blocker lists), ray-triangle tests against blocker lists.
struct DirectCost {
    double lights = 0, rays = 0, tests = 0;
};

struct DirectMethod {
    std::string name;
    std::function<Rgb<float>(const ShadingPoint<float>&, DirectQueries&, DirectCost&)> shade;
    /// Work the method redoes for every image before its pass (sparse sampling's sample cuts):
    /// counted in its row's seconds and per-pixel cost, as Fernandez 2004's tables count it.
    double per_image_seconds = 0;
    DirectCost per_image_cost{};
};

/// Methods and the rows of their precomputation ("<name>-build": seconds only).
struct DirectMethods {
    std::vector<DirectMethod> methods;
    std::vector<DirectRow> builds;
};

/// The scene and image a measurement renders; lights: its point lights as LIE lights (the
/// shadow-ray view every method shares).
struct DirectScene {
    const Scene<float>& scene;
    const DirectAccel& accel;
    int width = 128, height = 128;
    std::vector<LieLight<float>> lights = lie_lights(scene, 1);
};

/// `s` with its polygon area lights replaced by `points` oriented points in all (shared out by
/// area, lights/light_points.hpp), appended to its point lights; the polygons stay as geometry.
inline Scene<float> points_scene(Scene<float> s, std::size_t points) {
    LightPointOptions<float> o;
    o.total = points;
    s.point_lights = scene_light_points(s, o);
    s.area_lights.clear();
    std::fill(s.light_of.begin(), s.light_of.end(), -1);
    return s;
}

/// The standard ray tracer: a shadow ray to every light with a non-zero unoccluded contribution.
inline DirectMethod standard_method(const DirectScene& d) {
    return {"standard", [&d](const ShadingPoint<float>& sp, DirectQueries& q, DirectCost& c) {
                Rgb<float> L(0.0f), f;
                for (const LieLight<float>& l : d.lights) {
                    if (!point_light_unshadowed(l.light, sp, f)) continue;
                    c.lights += 1, c.rays += 1;
                    if (q.unoccluded(lie_shadow_ray(sp, l))) L += f;
                }
                return L;
            }};
}

/// Camera rays and their hits only, no light: what every method's time includes.
inline DirectMethod camera_method() {
    return {"camera", [](const ShadingPoint<float>&, DirectQueries&, DirectCost&) { return Rgb<float>(0.0f); }};
}

/// Every light evaluated without a visibility test: the floor of any method that evaluates every light.
inline DirectMethod no_shadows_method(const DirectScene& d) {
    return {"no-shadows", [&d](const ShadingPoint<float>& sp, DirectQueries&, DirectCost& c) {
                Rgb<float> L(0.0f), f;
                for (const LieLight<float>& l : d.lights)
                    if (point_light_unshadowed(l.light, sp, f)) c.lights += 1, L += f;
                return L;
            }};
}

/// "lie" and "lie-mask" (the same LIEs, masking on and off), built single-threaded from the
/// camera's view at the image's aspect.
inline DirectMethods lie_methods(const DirectScene& d, LieSettings s) {
    s.aspect = double(d.width) / double(d.height);
    s.threads = 1;
    const auto t0 = std::chrono::steady_clock::now();
    auto plain = std::make_shared<const LieDirect<float>>(d.scene, d.accel, s, false);
    const double build = seconds_since(t0);
    auto masked = std::make_shared<const LieDirect<float>>(plain->with_masking(true));
    auto method = [](const char* name, std::shared_ptr<const LieDirect<float>> lie) {
        return DirectMethod{name, [lie](const ShadingPoint<float>& sp, DirectQueries& q, DirectCost& c) {
                                const auto shaded = lie->shade(sp, q);
                                c.lights += shaded.cost.lights, c.rays += shaded.cost.accel_rays + shaded.cost.blocker_rays;
                                c.tests += shaded.cost.blocker_tests;
                                return shaded.L;
                            }};
    };
    return {{method("lie", plain), method("lie-mask", masked)}, {{d.scene.name, "lie-build", d.lights.size(), 0, 0, build}}};
}

/// "cuts-<threshold>" for each threshold: dense cuts (largest cut max_nodes) through one
/// cluster tree over the scene's point lights; one shadow ray per node with a non-zero f G.
inline DirectMethods cut_methods(const DirectScene& d, const std::vector<double>& thresholds, int max_nodes) {
    const auto t0 = std::chrono::steady_clock::now();
    auto tree = std::make_shared<const LightClusterTree<float>>(d.scene.point_lights);
    DirectMethods out;
    out.builds.push_back({d.scene.name, "cuts-build", d.lights.size(), 0, 0, seconds_since(t0)});
    for (const double t : thresholds) {
        const CutSettings cs{t, max_nodes};
        cs.validate();
        char name[32];
        std::snprintf(name, sizeof name, "cuts-%g", t);
        out.methods.push_back({name, [tree, cs](const ShadingPoint<float>& sp, DirectQueries& q, DirectCost& c) {
                                   const CutReceiver<float> r{sp.x, sp.n, sp.frame, sp.brdf, 0.0f};
                                   const auto cut = evaluate_cut(*tree, r, cs, [&](const PointLight<float>& l) {
                                       return q.unoccluded(lie_shadow_ray(sp, LieLight<float>{l}));
                                   });
                                   c.lights += cut.nodes, c.rays += cut.shadow_rays;
                                   return cut.L;
                               }});
    }
    return out;
}

/// Fernandez 2004, §5.3-5.4's sparse sampling over the scene's lights: "sparse-interp"
/// (interpolation) and "sparse-recon-<t>" (reconstruction cuts, agreement tolerance t) from one
/// set of sample cuts at `samples` Halton camera rays (a fraction `priority` of them placed by
/// §5.4.3's priorities), single thread. The sample cuts are
/// redone for every image: their seconds, lights and rays are in both rows (per_image_*);
/// the cluster tree's build is the "sparse-build" row.
inline DirectMethods sparse_methods(const DirectScene& d, int samples, double agreement, double priority, const CutSettings& cut) {
    SparseSettings s;
    s.mode = SparseMode::interpolate, s.samples = samples, s.agreement = agreement, s.cut = cut, s.threads = 1;
    s.priority = priority;
    s.aspect = double(d.width) / double(d.height);
    const auto t0 = std::chrono::steady_clock::now();
    const CutDirect<float> tree_only(d.scene, LightPointOptions<float>{}, cut);  // the tree's build alone
    const double tree_seconds = seconds_since(t0);
    const auto t1 = std::chrono::steady_clock::now();
    auto interp = std::make_shared<const SparseDirect<float>>(d.scene, d.accel, LightPointOptions<float>{}, s);
    const double per_image = std::max(0.0, seconds_since(t1) - tree_seconds);
    auto recon = std::make_shared<const SparseDirect<float>>(interp->with(SparseMode::reconstruct, agreement));
    const SparseSamples<float>& S = interp->samples();
    const DirectCost sample_cuts{double(S.cut_nodes()), double(S.shadow_rays()), 0};
    DirectMethods out;
    out.builds.push_back({d.scene.name, "sparse-build", d.lights.size(), 0, 0, tree_seconds});
    const std::string t = std::to_string(agreement).substr(0, 4);
    for (const auto& [name, m] : {std::pair{std::string("sparse-interp"), interp}, std::pair{"sparse-recon-" + t, recon}})
        out.methods.push_back({name,
                               [m](const ShadingPoint<float>& sp, DirectQueries& q, DirectCost& c) {
                                   const auto r = m->shade(sp, q);
                                   c.lights += r.nodes, c.rays += r.shadow_rays;
                                   return r.L;
                               },
                               per_image, sample_cuts});
    return out;
}

/// One pass of method m over the image: per-pixel luminance, summed cost, seconds.
struct DirectImage {
    std::vector<float> L;
    DirectCost cost;
    double seconds = 0;
};

inline DirectImage direct_pass(const DirectScene& d, const DirectMethod& m) {
    DirectImage out;
    out.L.assign(std::size_t(d.width) * std::size_t(d.height), 0.0f);
    const float aspect = float(d.width) / float(d.height);
    const auto t0 = std::chrono::steady_clock::now();
    for (int y = 0; y < d.height; ++y)
        for (int x = 0; x < d.width; ++x) {
            const Ray<float> ray = d.scene.camera.ray((float(x) + 0.5f) / float(d.width), (float(y) + 0.5f) / float(d.height), aspect);
            std::optional<SurfaceBrdf<float>> brdf;
            ShadingPoint<float> sp;
            if (!lie_camera_point(d.scene, d.accel, ray, brdf, sp)) continue;
            DirectQueries q(d.accel);
            out.L[std::size_t(y) * std::size_t(d.width) + std::size_t(x)] = m.shade(sp, q, out.cost).luminance();
        }
    out.seconds = seconds_since(t0);
    return out;
}

/// Fernandez 2004's eq. 4.3 at one pixel: min(|l - l_exact| / l_exact, 1) on luminance (a
/// pixel with l_exact = 0 counts 0 if l = 0, else 1); E is its mean over the pixels.
inline double error_e_term(double l, double l_exact) {
    const double diff = std::abs(l - l_exact);
    return l_exact > 0 ? std::min(diff / l_exact, 1.0) : (diff > 0 ? 1.0 : 0.0);
}

/// Method `name`'s row from its image, E and rmse against the reference luminance `ref`.
inline DirectRow direct_row(const DirectScene& d, const std::string& name, const DirectImage& img, std::span<const float> ref) {
    double e = 0, se = 0;
    for (std::size_t i = 0; i < img.L.size(); ++i) {
        const double diff = double(img.L[i]) - double(ref[i]);
        e += error_e_term(double(img.L[i]), double(ref[i]));
        se += diff * diff;
    }
    const double px = double(img.L.size());
    return {d.scene.name, name, d.lights.size(), img.cost.lights / px, img.cost.rays / px, img.seconds, e / px,
            std::sqrt(se / px), img.cost.tests / px};
}

/// Rows of `methods` (the first is the reference, "standard"), alternating over `reps`
/// repetitions, the best time of each; `reference` receives the first method's image.
inline std::vector<DirectRow> measure_direct(const DirectScene& d, const std::vector<DirectMethod>& methods, int reps,
                                             std::vector<float>* reference = nullptr) {
    const std::size_t n = methods.size();
    std::vector<DirectImage> best(n);
    for (int r = 0; r < std::max(reps, 1); ++r)
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t m = (k + std::size_t(r)) % n;
            DirectImage img = direct_pass(d, methods[m]);
            if (r == 0 || img.seconds < best[m].seconds) best[m] = std::move(img);
        }
    std::vector<DirectRow> rows;
    const double px = double(d.width) * double(d.height);
    for (std::size_t m = 0; m < n; ++m) {
        DirectRow row = direct_row(d, methods[m].name, best[m], best[0].L);
        row.seconds += methods[m].per_image_seconds;
        row.lights_per_pixel += methods[m].per_image_cost.lights / px;
        row.shadow_rays_per_pixel += methods[m].per_image_cost.rays / px;
        rows.push_back(row);
    }
    if (reference) *reference = best[0].L;
    return rows;
}

}  // namespace glint::bench
