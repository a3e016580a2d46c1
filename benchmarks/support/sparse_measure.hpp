// benchmarks/support/sparse_measure.hpp: direct illumination through sparse sampling
// (lights/sparse_direct.hpp: interpolation and reconstruction cuts) against dense cuts and the
// standard ray tracer on one scene: what bench_lights' sparse rows measure.
//
// Every pixel: one camera ray through its centre and the direct light at its diffuse hit from
// the scene's lights as one set of points (point lights as themselves, area lights split into
// LightPointOptions' points). Methods, timed alternately (rep r runs them in rotated order; the
// best time of each is kept), single thread:
//   "standard"  every light whose unoccluded contribution is not 0 gets a shadow ray (the exact
//               image: the reference of error_E and rmse),
//   "cuts"      the dense cut (CutSettings),
//   "sparse-interp-N", "sparse-recon-N-t"  N construction camera rays (sample cuts), agreement t.
// A sparse method's seconds are its construction's sample cuts (timed once, single thread; the
// cluster tree's build, shared with "cuts", is in no row) plus its pass; its rays and nodes per
// pixel count the sample cuts' too, spread over the pixels (as Fernandez 2004's tables do).
// error_E is eq. 4.3, the mean over pixels of min(|L - L_exact| / L_exact, 1) on luminance (a
// pixel with L_exact = 0 counts 0 if L = 0, else 1); rmse: of L - L_exact (luminance) over pixels.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <glint/lights/sparse_direct.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "lie_measure.hpp"

namespace glint::bench {

/// bench_lights' row (blocker_tests_per_pixel stays 0 here).
using SparseRow = LieRow;

/// What a row's CSV columns leave out.
struct SparseExtras {
    double dense_share = 0, build_seconds = 0, bytes_per_sample = 0;
};

struct SparseMeasureOptions {
    int width = 128, height = 128, reps = 2;
    std::vector<int> samples{5000};         // construction camera rays, one setting per value
    std::vector<double> agreements{0.05};   // t_interp of the reconstruction rows
    int neighbours = 8;
    double max_radius = 0.1;  // SparseSettings::max_radius
    LightPointOptions<float> lights{};
    CutSettings cut{};
};

namespace detail {

using SparseAccel = MeshBvh<MollerTrumbore<float>, 8>;

/// One method's shading of a point: its light, nodes (lights evaluated) and shadow rays.
struct SparseShade {
    Rgb<float> L{0.0f};
    int nodes = 0, rays = 0;
    bool dense = false;  // a sparse method fell back to the dense cut
};
using SparseMethod = std::function<SparseShade(const ShadingPoint<float>&, RayQueries<SparseAccel>&)>;

struct SparsePass {
    std::vector<float> L;
    double nodes = 0, rays = 0, seconds = 0, dense = 0;
};

/// The standard ray tracer over the tree's lights.
inline SparseShade sparse_standard(const LightClusterTree<float>& tree, const ShadingPoint<float>& sp, RayQueries<SparseAccel>& q) {
    const CutReceiver<float> r{sp.x, sp.n, sp.frame, sp.brdf, 0.0f};
    SparseShade out;
    for (const PointLight<float>& l : tree.lights()) {
        const Rgb<float> f = light_factor(l, r);
        if (!(f.max() > 0.0f)) continue;
        ++out.nodes;
        ++out.rays;
        if (CutDirect<float>::visible(sp, l, q)) out.L += f * l.intensity;
    }
    return out;
}

/// One pass of method m over the image: camera rays through pixel centres, m at the hits.
inline SparsePass sparse_pass(const Scene<float>& scene, const SparseAccel& accel, const SparseMethod& m, int w, int h) {
    SparsePass out;
    out.L.assign(std::size_t(w) * std::size_t(h), 0.0f);
    RayQueries<SparseAccel> q(accel);
    const auto start = std::chrono::steady_clock::now();
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Ray<float> ray = scene.camera.ray((float(x) + 0.5f) / float(w), (float(y) + 0.5f) / float(h), float(w) / float(h));
            std::optional<SurfaceBrdf<float>> brdf;
            ShadingPoint<float> sp;
            if (!lie_camera_point(scene, accel, ray, brdf, sp)) continue;
            const SparseShade s = m(sp, q);
            out.L[std::size_t(y) * std::size_t(w) + std::size_t(x)] = s.L.luminance();
            out.nodes += s.nodes;
            out.rays += s.rays;
            out.dense += s.dense;
        }
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

/// Eq. 4.3's E and the RMSE of `img` against `ref`.
inline std::pair<double, double> sparse_errors(const std::vector<float>& img, const std::vector<float>& ref) {
    double e = 0, se = 0;
    for (std::size_t i = 0; i < img.size(); ++i) {
        const double d = std::abs(double(img[i]) - double(ref[i]));
        e += ref[i] > 0 ? std::min(d / double(ref[i]), 1.0) : (d > 0 ? 1.0 : 0.0);
        se += d * d;
    }
    const double n = double(std::max<std::size_t>(img.size(), 1));
    return {e / n, std::sqrt(se / n)};
}

}  // namespace detail

/// The rows "standard", "cuts" and, per samples setting, "sparse-interp-N" and per agreement
/// "sparse-recon-N-t", for `scene`; `extras`, when given, receives per row the fraction of pixels
/// that a sparse method shaded by the dense cut (too few samples near, glossy), the seconds of
/// its sample cuts (in the row's seconds) and their bytes per sample.
inline std::vector<SparseRow> measure_sparse(const Scene<float>& scene, const SparseMeasureOptions& o,
                                             std::vector<SparseExtras>* extras = nullptr) {
    using namespace detail;
    const SparseAccel accel(std::span<const TriangleVertices<float>>(scene.triangles));
    struct Method {
        std::string name;
        SparseMethod run;
        double build = 0, build_nodes = 0, build_rays = 0, bytes = 0;
    };
    std::vector<Method> methods;
    std::vector<SparseDirect<float>> sparse;  // kept alive for the methods' lambdas
    sparse.reserve(o.samples.size() * (1 + o.agreements.size()));
    const CutDirect<float> dense(scene, o.lights, o.cut);
    const LightClusterTree<float>& tree = dense.tree();
    methods.push_back({"standard", [&](const ShadingPoint<float>& sp, RayQueries<SparseAccel>& q) { return sparse_standard(tree, sp, q); }});
    methods.push_back({"cuts", [&](const ShadingPoint<float>& sp, RayQueries<SparseAccel>& q) {
                           const CutReceiver<float> r{sp.x, sp.n, sp.frame, sp.brdf, 0.0f};
                           const auto c = evaluate_cut(tree, r, o.cut, [&](const PointLight<float>& l) { return CutDirect<float>::visible(sp, l, q); });
                           return SparseShade{c.L, c.nodes, c.shadow_rays};
                       }});
    for (const int n : o.samples) {
        SparseSettings s{.mode = SparseMode::interpolate, .samples = n, .neighbours = o.neighbours};
        s.max_radius = o.max_radius;
        s.aspect = double(o.width) / double(o.height);
        s.threads = 1;
        s.cut = o.cut;
        const auto t0 = std::chrono::steady_clock::now();
        const CutDirect<float> tree_only(scene, o.lights, o.cut);  // the tree's build, taken out below
        const auto t1 = std::chrono::steady_clock::now();
        sparse.emplace_back(scene, accel, o.lights, s);
        const auto t2 = std::chrono::steady_clock::now();
        const double build = std::max(0.0, std::chrono::duration<double>((t2 - t1) - (t1 - t0)).count());
        const SparseSamples<float>& S = sparse.back().samples();
        std::vector<std::pair<std::string, double>> modes{{"sparse-interp-" + std::to_string(n), -1.0}};
        for (const double t : o.agreements) modes.push_back({"sparse-recon-" + std::to_string(n) + "-" + std::to_string(t).substr(0, 5), t});
        const SparseDirect<float>& base = sparse.back();
        for (const auto& [name, t] : modes) {
            if (t >= 0) sparse.push_back(base.with(SparseMode::reconstruct, t));
            const SparseDirect<float>& d = t >= 0 ? sparse.back() : base;
            methods.push_back({name, [&d](const ShadingPoint<float>& sp, RayQueries<SparseAccel>& q) {
                                   const auto r = d.shade(sp, q);
                                   return SparseShade{r.L, r.nodes, r.shadow_rays, r.dense};
                               }, build, double(S.cut_nodes()), double(S.shadow_rays()), S.bytes_per_sample()});
        }
    }
    std::vector<SparsePass> best(methods.size());
    for (int rep = 0; rep < std::max(o.reps, 1); ++rep)
        for (std::size_t k = 0; k < methods.size(); ++k) {
            const std::size_t m = (k + std::size_t(rep)) % methods.size();
            SparsePass p = sparse_pass(scene, accel, methods[m].run, o.width, o.height);
            if (rep == 0 || p.seconds < best[m].seconds) best[m] = std::move(p);
        }
    const double px = double(o.width) * double(o.height);
    std::vector<SparseRow> rows;
    if (extras) extras->clear();
    for (std::size_t m = 0; m < methods.size(); ++m) {
        if (extras) extras->push_back({best[m].dense / px, methods[m].build, methods[m].bytes});
        const auto [E, rmse] = sparse_errors(best[m].L, best[0].L);
        rows.push_back({scene.name, methods[m].name, tree.lights().size(), (best[m].nodes + methods[m].build_nodes) / px,
                        (best[m].rays + methods[m].build_rays) / px, best[m].seconds + methods[m].build, E, rmse, 0});
    }
    return rows;
}

}  // namespace glint::bench
