// benchmarks/support/direct_section.hpp: bench_lights' "direct" section: on the three
// generated many-light scenes (lights/scenes.hpp: hall, kitchen with its disk lights split into
// oriented points, lie-hall), direct illumination at the primary hits by every method of
// `direct_methods` against the standard ray tracer (support/direct_measure.hpp), and the
// summary: speedups beside Fernandez 2004's, and the standard ray tracer's cost per shadow ray
// and its floor (camera rays and every light shaded, no shadows), the measured reason where a
// speedup falls short of the seed's.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <glint/lights/scenes.hpp>

#include "flags.hpp"  // cli/: the command-line conventions
#include "support/direct_measure.hpp"

namespace glint::bench {

struct DirectOptions {
    int size = 128, reps = 3;
    int hall_sides = 128, hall_rings = 256, pillar_sides = 128, pillar_rings = 128;
    std::size_t kitchen_points = 4608;
    std::vector<double> thresholds{0.02, 0.01};
    int max_nodes = 300;
    int sparse_samples = 0;          // sample cuts per image (0: the seed's density, 5000 on 512²)
    double sparse_agreement = 0.05;  // reconstruction's agreement tolerance (eq. 5.20)
    double sparse_priority = 0.0;    // the fraction of sample cuts placed by priority (§5.4.3)
    LieSettings lie = [] {
        LieSettings s;
        s.samples = 1 << 15;
        s.subdivision = LieSubdivision::adaptive;
        return s;
    }();

    void quick() {
        size = 24, reps = 1, hall_sides = 8, hall_rings = 1, pillar_sides = 8, pillar_rings = 1;
        kitchen_points = 512, lie.samples = 1024;
    }
    /// The section's flags (--help lists them under "Direct section").
    void add_flags(cli::App& app) {
        const std::string g = "Direct section";
        cli::number(app, "--direct-size", size, 1, 1 << 14, "image width and height")->group(g);
        cli::number(app, "--direct-reps", reps, 1, 1000, "timed repetitions (best of)")->group(g);
        cli::number(app, "--hall-sides", hall_sides, 3, 1 << 16, "hall: sides of a column")->group(g);
        cli::number(app, "--hall-rings", hall_rings, 1, 1 << 16, "hall: rings of a column")->group(g);
        cli::number(app, "--pillar-sides", pillar_sides, 3, 1 << 16, "lie-hall: sides of a pillar")->group(g);
        cli::number(app, "--pillar-rings", pillar_rings, 1, 1 << 16, "lie-hall: rings of a pillar")->group(g);
        cli::number(app, "--kitchen-points", kitchen_points, std::size_t(72), std::size_t(1) << 24,
                    "kitchen: oriented points of the 72 disk lights")->group(g);
        cli::numbers(app, "--thresholds", thresholds, 0.0, 1.0, "cut thresholds")->group(g);
        cli::number(app, "--max-nodes", max_nodes, 0, 1 << 30, "largest cut (0: unlimited)")->group(g);
        cli::number(app, "--sparse-samples", sparse_samples, 0, 1 << 24, "sample cuts per image (0: the seed's density)")
            ->group(g);
        cli::number(app, "--sparse-agreement", sparse_agreement, 0.0, 1e6, "reconstruction's agreement tolerance")->group(g);
        cli::number(app, "--sparse-priority", sparse_priority, 0.0, 0.999, "the fraction of sample cuts placed by priority")
            ->group(g);
        cli::number(app, "--lie-samples", lie.samples, 1, 1 << 30, "LIE: image samples of the construction")->group(g);
        cli::number_to<int>(app, "--depth", [this](int d) { lie.subdivision = LieSubdivision::fixed, lie.depth = d; }, 0, 20,
                            "LIE: fixed subdivision at this depth (default: adaptive)")->group(g);
        cli::number_to<int>(app, "--adaptive", [this](int b) {
            lie.subdivision = LieSubdivision::adaptive, lie.blocker_threshold = b;
        }, 1, 1 << 20, "LIE: adaptive subdivision, split past this many blockers (default 8)")->group(g);
        app.flag("--three-state", [this] { lie.variant = LieVariant::three_state; }, "LIE: three states without blocker lists")
            ->group(g);
    }
    /// Checks what the library validates (the cuts' and LIE's settings) before any work starts;
    /// the flags' ranges are checked while the command line is parsed.
    void validate() const {
        for (const double t : thresholds) CutSettings{t, max_nodes}.validate();
        lie.validate();
    }
};

/// The scene `name` at the section's sizes; area lights as oriented points.
inline Scene<float> direct_scene(const std::string& name, const DirectOptions& o) {
    if (name == "hall") return hall_scene<float>(o.hall_sides, o.hall_rings);
    if (name == "kitchen") return points_scene(kitchen_scene<float>(), o.kitchen_points);
    if (name == "lie-hall") return lie_hall_scene<float>(o.pillar_sides, o.pillar_rings);
    throw Error("unknown direct scene '" + name + "' (hall, kitchen, lie-hall)");
}

inline void append(DirectMethods& to, DirectMethods from) {
    for (auto& m : from.methods) to.methods.push_back(std::move(m));
    for (auto& b : from.builds) to.builds.push_back(std::move(b));
}

/// The methods measured against the standard ray tracer (which comes first), one factory
/// each; sparse sampling at the seed's density (5000 samples on 512², scaled to the image) and
/// the first cut threshold.
inline DirectMethods direct_methods(const DirectScene& d, const DirectOptions& o) {
    DirectMethods out{{standard_method(d), camera_method(), no_shadows_method(d)}, {}};
    append(out, lie_methods(d, o.lie));
    append(out, cut_methods(d, o.thresholds, o.max_nodes));
    const int samples = o.sparse_samples > 0 ? o.sparse_samples : std::max(64, int(5000.0 * o.size * o.size / (512.0 * 512.0)));
    append(out, sparse_methods(d, samples, o.sparse_agreement, o.sparse_priority, CutSettings{o.thresholds.front(), o.max_nodes}));
    return out;
}

/// Every method's rows, then the builds', for each scene of `scenes`.
inline std::vector<DirectRow> direct_section(const DirectOptions& o, const std::vector<std::string>& scenes) {
    std::vector<DirectRow> rows;
    for (const std::string& name : scenes) {
        const Scene<float> s = direct_scene(name, o);
        const auto t0 = std::chrono::steady_clock::now();
        const DirectAccel accel(std::span<const TriangleVertices<float>>(s.triangles));
        std::fprintf(stderr, "%s: %zu triangles, %zu lights, BVH in %.1f s\n", name.c_str(), s.triangles.size(),
                     s.point_lights.size(), seconds_since(t0));
        const DirectScene d{s, accel, o.size, o.size};
        const DirectMethods ms = direct_methods(d, o);
        for (const DirectRow& r : measure_direct(d, ms.methods, o.reps)) rows.push_back(r);
        for (const DirectRow& r : ms.builds) rows.push_back(r);
    }
    return rows;
}

/// Fernandez 2004's number for (scene, method family), or "".
inline std::string seed_number(const std::string& scene, const std::string& method) {
    const bool cuts = method.rfind("cuts-", 0) == 0;
    if (scene == "hall" && cuts) return "2.8x (831 lights, 626->118 rays/px), 3.86x (839)";
    if (scene == "kitchen" && cuts) return "11.5x (4608 oriented, 976->141 rays/px)";
    if (scene == "hall" && method == "lie") return "14.6x (70 spots, 240k polygons)";
    if (scene == "kitchen" && method == "lie") return "11.5x (one area light, 7k polygons)";
    if (scene == "lie-hall" && method == "lie") return "24.1x (100 point lights, 980k polygons)";
    if (scene == "lie-hall" && method == "lie-mask") return "29.2x (with masking)";
    const bool recon = method.rfind("sparse-recon", 0) == 0;
    if (scene == "hall" && method == "sparse-interp") return "83.4x (831 lights), 64.1x (839)";
    if (scene == "kitchen" && method == "sparse-interp") return "328x (4608 oriented)";
    if (scene == "hall" && recon) return "33.9x (831 lights), 15.3x (839)";
    if (scene == "kitchen" && recon) return "51.1x (4608 oriented)";
    return "";
}

inline bool is_build(const DirectRow& r) { return r.method.find("-build") != std::string::npos; }
/// A method's family: "cuts" for every cuts-<threshold>, "sparse-recon" for every agreement, else its name.
inline std::string family(const std::string& method) {
    if (method.rfind("sparse-recon", 0) == 0) return "sparse-recon";
    return method.rfind("cuts-", 0) == 0 ? "cuts" : method;
}

/// The fastest row of each method family at E <= 2% on `scene`.
inline std::map<std::string, const DirectRow*> best_at_two_percent(const std::string& scene, const std::vector<DirectRow>& rows) {
    std::map<std::string, const DirectRow*> best;
    for (const DirectRow& r : rows) {
        const std::string fam = family(r.method);
        if (r.scene != scene || is_build(r) || fam == "standard" || fam == "camera" || fam == "no-shadows" || r.error_E > 0.02)
            continue;
        if (!best[fam] || r.seconds < best[fam]->seconds) best[fam] = &r;
    }
    return best;
}

/// Per scene, where the time goes: camera rays, per light shaded, per shadow ray of the
/// standard ray tracer, per cut node (beyond its shadow ray); the floor (camera rays and every
/// light shaded, no shadows); each family's fastest row at E <= 2%.
inline void print_direct_reasons(std::FILE* f, const std::string& scene, const std::vector<DirectRow>& rows, double pixels) {
    std::map<std::string, const DirectRow*> m;
    for (const DirectRow& r : rows)
        if (r.scene == scene) m[r.method] = &r;
    const DirectRow *st = m["standard"], *cam = m["camera"], *ns = m["no-shadows"];
    if (!st) return;
    if (cam && ns) {
        const double ray = (st->seconds - ns->seconds) / (st->shadow_rays_per_pixel * pixels);
        std::fprintf(f, "%-8s camera rays %.3f s; %.0f ns per light shaded, %.0f ns per shadow ray (standard), %.0f of %zu lights "
                        "shaded per pixel; floor (camera rays, every light shaded, no shadows) %.3f s = %.1fx",
                     scene.c_str(), cam->seconds, 1e9 * (ns->seconds - cam->seconds) / (ns->lights_per_pixel * pixels), 1e9 * ray,
                     st->lights_per_pixel, st->lights, ns->seconds, st->seconds / ns->seconds);
        for (const auto& [name, r] : m)
            if (r && family(name) == "cuts" && !is_build(*r))
                std::fprintf(f, "; %s %.0f ns per node beyond its ray", name.c_str(),
                             1e9 * (r->seconds - cam->seconds - ray * r->shadow_rays_per_pixel * pixels) / (r->lights_per_pixel * pixels));
        std::fprintf(f, "\n");
    }
    std::fprintf(f, "%-8s at E <= 2%%:", scene.c_str());
    for (const auto& [fam, r] : best_at_two_percent(scene, rows))
        if (r) std::fprintf(f, " %s %.2fx (%s, E %.2f%%);", fam.c_str(), st->seconds / r->seconds, r->method.c_str(), 100 * r->error_E);
    std::fprintf(f, "\n");
}

/// The side-by-side table (speedups beside Fernandez 2004's), then each scene's reasons.
inline void print_direct_summary(std::FILE* f, const std::vector<DirectRow>& rows, double pixels) {
    std::vector<std::string> scenes;
    std::map<std::string, double> standard;
    for (const DirectRow& r : rows) {
        if (std::find(scenes.begin(), scenes.end(), r.scene) == scenes.end()) scenes.push_back(r.scene);
        if (r.method == "standard") standard[r.scene] = r.seconds;
    }
    std::fprintf(f, "\n%-8s %-10s %9s %9s %8s %8s %7s  %s\n", "scene", "method", "lights/px", "rays/px", "seconds", "speedup",
                 "E", "Fernandez 2004");
    for (const DirectRow& r : rows) {
        if (is_build(r) || !standard.count(r.scene)) continue;
        std::fprintf(f, "%-8s %-10s %9.1f %9.1f %8.3f %7.2fx %6.2f%%%s %s\n", r.scene.c_str(), r.method.c_str(), r.lights_per_pixel,
                     r.shadow_rays_per_pixel, r.seconds, standard[r.scene] / r.seconds, 100 * r.error_E, r.error_E <= 0.02 ? " " : "!",
                     seed_number(r.scene, r.method).c_str());
    }
    for (const std::string& scene : scenes) print_direct_reasons(f, scene, rows, pixels);
    std::fprintf(f, "(! marks E > 2%%; sparse rows include their per-image sample cuts; precomputation, not in the times:");
    for (const DirectRow& r : rows)
        if (is_build(r)) std::fprintf(f, " %s %s %.2f s;", r.scene.c_str(), r.method.c_str(), r.seconds);
    std::fprintf(f, ")\n");
}

}  // namespace glint::bench
