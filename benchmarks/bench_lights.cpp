// bench_lights: many-light direct lighting, two sections (--mode direct|path|all, default all).
//
// direct (support/direct_section.hpp): on hall (1.3M triangles), kitchen (its 72 disk lights as
// 4608 oriented points) and lie-hall (820k triangles), direct illumination at the primary hits
// (one camera ray per pixel, single thread, methods alternating, best of --direct-reps) by the
// standard ray tracer (a shadow ray per light through the 8-wide BVH), camera rays alone, no
// shadows (the floor), LIE with and without masking and dense cuts at each threshold; error_E
// against the standard ray tracer's image; the summary prints each speedup beside Fernandez
// 2004's, where the time goes (per shadow ray, per light shaded, per cut node) and each
// method's fastest row at E <= 2%. Options: --direct-size N (128), --direct-reps N (3),
// --hall-sides N (128), --hall-rings N (256), --pillar-sides N (128), --pillar-rings N (128),
// --kitchen-points N (4608), --thresholds a,b (0.02,0.01), --max-nodes N (300),
// --lie-samples N (32768), --depth N | --adaptive T (default adaptive, 8), --three-state,
// --sparse-samples N (0: 5000 on 512², scaled), --sparse-agreement T (0.05), --sparse-priority P
// (0: uniform samples; P: that fraction placed by Fernandez 2004, §5.4.3's priorities).
//
// path: the path tracer, error against time. Per scene
// (hall, kitchen), a high-spp reference (the light tree, all threads), then each method at
// equal spp on one thread, methods alternating per repetition (ABBA); one CSV row per method
// and repetition:
//   scene,method,lights,lights_per_pixel,shadow_rays_per_pixel,seconds,error_E,rmse
// lights: the scene's emitters; lights_per_pixel: light samples per pixel at the primary
// vertices (spp x light samples); shadow_rays_per_pixel: every ray the render traced per pixel
// (closest-hit and shadow rays: the tracer counts them together); error_E: Fernandez 2004's
// eq. 4.3, the mean over pixels of min(|L - L_ref| / L_ref, 1) (luminance); rmse over pixels
// and bands; seconds: the render's CPU seconds (process time around it, one thread). The
// summary prints each method's MSE x time against power selection's.
// Methods: power, tree (glint-render --direct mis | tree) and power-estimate, tree-estimate
// (the same with --roulette estimate). Each is a small function (a row of `methods`), so that
// other methods join the table.
//
//   taskset -c 1 bench_lights [--quick] [--csv FILE] [--mode direct|path|all]
//                             [--scene hall|kitchen|lie-hall|all] [--size N]
//                             [--spp N] [--ref-spp N] [--reps N] [direct options]
//   taskset -c 1 bench_lights --tree-scaling [--csv FILE]   the light tree over 10^3, 10^4, 10^5
//                             random point, spot and oriented lights: build seconds, bytes per
//                             light, ns per pick (CSV lights,build_seconds,bytes_per_light,pick_ns)
//   taskset -c 1 bench_lights --pick-timing   ns per pick and per probability() on hall and
//                             kitchen at points uniform on their surfaces
// (support/light_tree_measure.hpp)
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/named_render.hpp>
#include "glint_instances.hpp"  // render_named for AnyAccel, compiled once (instances/)
#include <glint/tracer/scenes.hpp>

#include "support/direct_section.hpp"
#include "support/light_tree_measure.hpp"

using namespace glint;

namespace {

struct Options {
    std::string csv, scene = "all", mode = "all";
    int size = 64, spp = 16, ref_spp = 256, reps = 3;
    bench::DirectOptions direct;
    bool tree_scaling = false, pick_timing = false;
};

struct Row {
    std::string scene, method;
    std::size_t lights = 0;
    double lights_per_pixel = 0, rays_per_pixel = 0, seconds = 0, error_e = 0, rmse = 0;
};

/// Error E (eq. 4.3) and RMSE of `img` against `ref`.
void errors(const Image<Rgb<float>>& img, const Image<Rgb<float>>& ref, double& e, double& rmse) {
    double se = 0, sq = 0;
    for (std::size_t i = 0; i < img.size(); ++i) {
        se += bench::error_e_term(img.pixels[i].luminance(), ref.pixels[i].luminance());
        for (std::size_t c = 0; c < 3; ++c) sq += std::pow(double(img.pixels[i][c]) - double(ref.pixels[i][c]), 2);
    }
    e = se / double(img.size());
    rmse = std::sqrt(sq / (3.0 * double(img.size())));
}

/// CPU seconds of this process (every thread): on a shared machine a one-thread render's CPU
/// time moves far less with the load than its wall time.
double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// The path tracer with a named direct-lighting policy; `seconds` is the render's CPU time.
RenderResult path_traced(const Scene<float>& s, const DefaultAccel& accel, const Options& o, const char* direct, int spp,
                         int threads, const char* roulette = "throughput") {
    NamedRender<float> r;
    r.image.width = r.image.height = o.size;
    r.image.spp = spp;
    r.image.threads = threads;
    r.direct = direct;
    r.roulette = roulette;
    r.seed = 1;
    const double t0 = cpu_seconds();
    RenderResult out = render_named(s, any_accel_view(accel), r);
    out.seconds = cpu_seconds() - t0;
    return out;
}

/// A method: its row from one render of scene s against the reference.
using Method = Row (*)(const Scene<float>&, const DefaultAccel&, const Options&, const Image<Rgb<float>>&);

Row measured(const char* name, const RenderResult& r, const Scene<float>& s, const Options& o, const Image<Rgb<float>>& ref) {
    Row row{s.name, name, s.area_lights.size() + s.point_lights.size()};
    const double pixels = double(o.size) * double(o.size);
    row.lights_per_pixel = double(o.spp);
    row.rays_per_pixel = double(r.rays) / pixels;
    row.seconds = r.seconds;
    errors(r.image, ref, row.error_e, row.rmse);
    return row;
}

Row power(const Scene<float>& s, const DefaultAccel& a, const Options& o, const Image<Rgb<float>>& ref) {
    return measured("power", path_traced(s, a, o, "mis", o.spp, 1), s, o, ref);
}
Row tree(const Scene<float>& s, const DefaultAccel& a, const Options& o, const Image<Rgb<float>>& ref) {
    return measured("tree", path_traced(s, a, o, "tree", o.spp, 1), s, o, ref);
}

// The same with Szecsi 2009 2.3's radiance estimate in the roulette (glint-render --roulette
// estimate): shorter walks at equal or lower noise on these scenes.
Row power_estimate(const Scene<float>& s, const DefaultAccel& a, const Options& o, const Image<Rgb<float>>& ref) {
    return measured("power-estimate", path_traced(s, a, o, "mis", o.spp, 1, "estimate"), s, o, ref);
}
Row tree_estimate(const Scene<float>& s, const DefaultAccel& a, const Options& o, const Image<Rgb<float>>& ref) {
    return measured("tree-estimate", path_traced(s, a, o, "tree", o.spp, 1, "estimate"), s, o, ref);
}

const std::pair<const char*, Method> methods[] = {
    {"power", power}, {"tree", tree}, {"power-estimate", power_estimate}, {"tree-estimate", tree_estimate}};

Options parse(int argc, char** argv) {
    Options o;
    cli::App app("bench_lights: the many-light methods (Fernandez 2004; lightcuts; the stochastic light tree) against the "
                 "standard ray tracer and power sampling, single thread");
    // --quick first: the flags after it in this list (any given with it) override its sizes.
    app.flag("--quick", [&o] { o.size = 24, o.spp = 4, o.ref_spp = 64, o.reps = 1, o.direct.quick(); }, "a smoke run");
    const std::array<Choice<int>, 3> modes{{{"all", "both sections", 0},
                                            {"direct", "direct light at the primary hits (Fernandez 2004's measure)", 1},
                                            {"path", "the path tracer, MSE x time at equal spp", 2}}};
    cli::choice(app, "--mode", o.mode, std::span<const Choice<int>>(modes), "mode", "what to measure");
    const std::array<Choice<int>, 4> scenes{{{"all", "the three scenes", 0}, {"hall", "800 point and spot lights", 1},
                                             {"kitchen", "72 disk lights", 2}, {"lie-hall", "100 point lights", 3}}};
    cli::choice(app, "--scene", o.scene, std::span<const Choice<int>>(scenes), "scene", "the scene");
    cli::output(app, "--csv", o.csv, "write the rows as CSV");
    cli::number(app, "--size", o.size, 1, 1 << 14, "path section: image width and height");
    cli::number(app, "--spp", o.spp, 1, 1 << 20, "path section: samples per pixel");
    cli::number(app, "--ref-spp", o.ref_spp, 1, 1 << 24, "path section: the reference's samples per pixel");
    cli::number(app, "--reps", o.reps, 1, 1000, "path section: timed repetitions");
    cli::flag(app, "--tree-scaling", o.tree_scaling, "the light tree's build and pick time against the light count");
    cli::flag(app, "--pick-timing", o.pick_timing, "time one light pick of each sampler");
    o.direct.add_flags(app);
    if (!cli::parse(app, argc, argv)) std::exit(0);
    o.direct.validate();
    return o;
}

/// The direct section's rows (support/direct_section.hpp) as this program's rows; its summary on stderr.
std::vector<Row> direct_rows(const Options& o) {
    std::vector<std::string> scenes;
    for (const char* name : {"hall", "kitchen", "lie-hall"})
        if (o.scene == "all" || o.scene == name) scenes.push_back(name);
    const auto rows = bench::direct_section(o.direct, scenes);
    bench::print_direct_summary(stderr, rows, double(o.direct.size) * double(o.direct.size));
    std::vector<Row> out;
    for (const auto& r : rows)
        out.push_back({r.scene, r.method, r.lights, r.lights_per_pixel, r.shadow_rays_per_pixel, r.seconds, r.error_E, r.rmse});
    return out;
}

/// --tree-scaling: the light tree's build time, bytes per light and pick time at 10^3..10^5 lights.
void tree_scaling_table(const Options& o) {
    std::FILE* out = o.csv.empty() ? stdout : std::fopen(o.csv.c_str(), "w");
    if (!out) throw Error("cannot write '" + o.csv + "'");
    std::fprintf(out, "lights,build_seconds,bytes_per_light,pick_ns\n");
    for (std::size_t n : {std::size_t(1000), std::size_t(10000), std::size_t(100000)}) {
        const bench::TreeScaling r = bench::tree_scaling(n, 7, o.reps);
        std::fprintf(out, "%zu,%.5f,%.1f,%.1f\n", r.lights, r.build_seconds, r.bytes_per_light, r.pick_ns);
        std::fflush(out);
    }
    if (out != stdout) std::fclose(out);
}

/// --pick-timing: ns per pick and per probability() on the two scenes.
void pick_timing_table(const Options& o) {
    std::printf("scene,lights,nodes,pick_ns,probability_ns\n");
    for (const char* name : {"hall", "kitchen"}) {
        if (o.scene != "all" && o.scene != name) continue;
        const Scene<float> s = builtin_scene<float>(name);
        const LightTree<float> tree(scene_light_bounds(s));
        const bench::PickTiming t = bench::pick_timing(tree, bench::surface_points(s, 200000, 3), o.reps);
        std::printf("%s,%zu,%zu,%.1f,%.1f\n", name, tree.size(), tree.nodes().size(), t.pick_ns, t.probability_ns);
    }
}

}  // namespace

int main(int argc, char** argv) try {
    const Options o = parse(argc, argv);
    if (o.tree_scaling) return tree_scaling_table(o), 0;
    if (o.pick_timing) return pick_timing_table(o), 0;
    std::vector<Row> rows, direct;
    if (o.mode != "path") direct = direct_rows(o);
    for (const char* name : {"hall", "kitchen"}) {
        if (o.mode == "direct") break;
        if (o.scene != "all" && o.scene != name) continue;
        const Scene<float> s = builtin_scene<float>(name);
        const DefaultAccel accel(s.triangles);
        const RenderResult ref = path_traced(s, accel, o, "tree", o.ref_spp, 0);
        std::fprintf(stderr, "%s: reference %d spp in %.1f CPU s\n", name, o.ref_spp, ref.seconds);
        const int m = int(std::size(methods));
        for (int rep = 0; rep < o.reps; ++rep)
            for (int k = 0; k < m; ++k) {
                const int j = rep % 2 ? m - 1 - k : k;  // ABBA
                rows.push_back(methods[j].second(s, accel, o, ref.image));
            }
    }
    std::FILE* out = o.csv.empty() ? stdout : std::fopen(o.csv.c_str(), "w");
    if (!out) throw Error("cannot write '" + o.csv + "'");
    std::fprintf(out, "scene,method,lights,lights_per_pixel,shadow_rays_per_pixel,seconds,error_E,rmse\n");
    for (const Row& r : direct) std::fprintf(out, "%s,%s,%zu,%.2f,%.2f,%.4f,%.5f,%.6g\n", r.scene.c_str(), r.method.c_str(),
                                              r.lights, r.lights_per_pixel, r.rays_per_pixel, r.seconds, r.error_e, r.rmse);
    for (const Row& r : rows)
        std::fprintf(out, "%s,%s,%zu,%.1f,%.1f,%.4f,%.5f,%.6g\n", r.scene.c_str(), r.method.c_str(), r.lights,
                     r.lights_per_pixel, r.rays_per_pixel, r.seconds, r.error_e, r.rmse);
    if (out != stdout) std::fclose(out);
    // Summary: per scene and method, median seconds and mean MSE, MSE x time against power's.
    std::map<std::pair<std::string, std::string>, std::vector<Row>> by;
    for (const Row& r : rows) by[{r.scene, r.method}].push_back(r);
    for (const auto& [key, rs] : by) {
        std::vector<double> t;
        double mse = 0;
        for (const Row& r : rs) t.push_back(r.seconds), mse += r.rmse * r.rmse / double(rs.size());
        std::sort(t.begin(), t.end());
        const auto& base = by[{key.first, "power"}];
        std::vector<double> tb;
        double mse_b = 0;
        for (const Row& r : base) tb.push_back(r.seconds), mse_b += r.rmse * r.rmse / double(base.size());
        std::sort(tb.begin(), tb.end());
        const double med = t[t.size() / 2], med_b = tb[tb.size() / 2];
        std::fprintf(stderr, "%-8s %-14s time %.3f s  MSE %.4g  E %.4f  MSE*time vs power %.3f\n", key.first.c_str(),
                     key.second.c_str(), med, mse, rs[0].error_e, mse * med / (mse_b * med_b));
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_lights: %s\n", e.what());
    return 1;
}
