// bench_cones: the hierarchical ray engine (Szécsi 2009, ch. 6) against brute force and
// glint's fastest tree, the wide BVH, on the refracted-ray passes of a glass object, versus
// triangle count.
//
// Szécsi 2009, §6.4: 256 x 256 rays in 16 x 16 tiles, maximum path length 5; the primary
// refracted rays come from rasterization (§6.3.2), and the timed work is the passes that trace
// them on. Here the primary hits are found once (untimed) with the wide BVH, shaded into the
// primary refracted rays, and then every method runs the same passes (trace, refract or
// reflect at the hit, drop the rays that leave) from the same rays:
//   brute  BruteForce<Ivm<float>>: every ray against every triangle (the ray engine);
//   tiles  RayTileEngine<Ivm<float>>: cones over 16 x 16 tiles, spheres per triangle;
//   tree   MeshBvh<Ivm<float>, 8> (8-wide BVH, trees/mesh_bvh.hpp; the IVM as in the tiles): its build
//          time is printed apart (dynamic geometry pays it every frame; not in `seconds`).
// tests_per_ray = ray-triangle tests / ray segments traced; the tree's tests are counted in
// a separate, untimed run with a counting copy of the IVM policy.
// Szécsi 2009 reports 2x over brute force at 100 triangles and 15-20x at 5000 (§6.4-6.5).
// Every speed claim is a ratio measured in the same run; the program also checks that the
// tiles' final rays are bit-identical to brute force's (exit status 1 if not).
//
//   bench_cones [--csv FILE] [--plot FILE.png] [--quick] [--scene sphere|knot] [--size N]
//               [--tile N] [--passes N] [--reps N] [--counts 100,1000,...]     (see --help)
// --quick: 64 x 64 rays, 100 and 1000 triangles, one repetition (CI smoke test); flags given
// with it override its values.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include <glint/cones/glass.hpp>
#include <glint/cones/ray_tiles.hpp>
#include <glint/intersection/ivm.hpp>
#include <glint/trees/brute_force.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include "tree_scenes.hpp"
#include <glint/trees/traversal.hpp>

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

/// The IVM policy with a counter of tests, for the tree's tests_per_ray (untimed run). The
/// counter is this benchmark's instrumentation, not library state.
thread_local std::uint64_t counted_tests = 0;

struct CountingIvm {
    using scalar_type = float;
    using frame = OffsetFrames;
    using RayData = Ivm<float>::RayData;
    Ivm<float> rec;

    static CountingIvm build(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return {Ivm<float>::build(a, b, c)}; }
    static RayData prepare(const Ray<float>& r) { return Ivm<float>::prepare(r); }
    bool test(const RayData& r, float& t, float& u, float& v) const {
        ++counted_tests;
        return rec.test(r, t, u, v);
    }
    static void batch(const RecordView<Ivm<float>>& v, std::size_t first, std::size_t n, const RayData& r, float* ts,
                      float* us, float* vs) {
        counted_tests += n;
        detail::batch<Ivm<float>>(v, first, n, r, ts, us, vs);
    }
};
static_assert(TriangleIntersector<CountingIvm>);

using Tree = MeshBvh<Ivm<float>, 8>;
using CountingTree = MeshBvh<CountingIvm, 8>;

struct Options {
    std::string csv, plot, scene = "sphere";
    bool quick = false;
    int size = 256, tile = 16, passes = 5, reps = 3;
    std::vector<int> counts{100, 1000, 5000, 50000};
};

struct Row {
    int triangles;
    std::string method;
    double seconds, tests_per_ray;
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The glass object with about n triangles: a UV sphere (2 * stacks * slices, slices = 2
/// stacks) or a torus knot tube (2 * segments * sides, segments = 5 sides).
Mesh<float> object_with(const std::string& scene, int n) {
    if (scene == "sphere") {
        const int stacks = std::max(2, int(std::lround(std::sqrt(n / 4.0))));
        return make_sphere<float>(stacks, std::max(3, n / (2 * stacks)));
    }
    const int sides = std::max(3, int(std::lround(std::sqrt(n / 10.0))));
    const int segments = std::max(3, n / (2 * sides));
    return make_torus_knot<float>(segments, sides);
}

/// Pinhole camera (one ray per pixel centre) looking down at the knot's centre, framed so
/// that the knot fills the image (000 section 6.4: a refractive surface in most pixels).
std::vector<Ray<float>> camera_rays(const AABB<float>& box, int size) {
    const Vec3d c(box.center());
    const double radius = 0.5 * glm::length(Vec3d(box.extent()));
    const Vec3d eye = c + 2.5 * radius * glm::normalize(Vec3d(0.2, -0.45, 1.0));
    const Vec3d fwd = glm::normalize(c - eye), right = glm::normalize(glm::cross(fwd, Vec3d(0, 0, 1)));
    const Vec3d up = glm::cross(right, fwd);
    const double half = 0.8 * radius / (2.5 * radius);  // tan of the half field of view
    std::vector<Ray<float>> rays(std::size_t(size) * size);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double sx = (2.0 * (x + 0.5) / size - 1.0) * half, sy = (1.0 - 2.0 * (y + 0.5) / size) * half;
            Ray<float>& r = rays[std::size_t(y) * size + x];
            r.origin = Vec3f(eye);
            r.direction = Vec3f(glm::normalize(fwd + sx * right + sy * up));
        }
    return rays;
}

/// The command line (cli/flags.hpp): exits after --help, --version or a bad flag. --quick sets
/// its sizes first, so that flags given explicitly override them.
void parse(int argc, char** argv, Options& o) {
    cli::App app("bench_cones: the ray-tile engine (Szecsi 2009, ch. 6) against brute force and the 8-wide BVH");
    const auto quick = [&o] {
        o.quick = true;
        o.size = 64;
        o.counts = {100, 1000};
        o.reps = 1;
    };
    app.flag("--quick", quick, "a smoke run: 64 x 64 rays, 100 and 1000 triangles, one repetition");
    cli::output(app, "--csv", o.csv, "write the rows as CSV (and a gnuplot plot beside it)");
    cli::output(app, "--plot", o.plot, "FILE.png: the plot (default: the CSV's name with .png)");
    static constexpr Choice<const char*> scenes[] = {{"sphere", "a UV sphere", "sphere"}, {"knot", "a torus knot tube", "knot"}};
    cli::choice(app, "--scene", o.scene, std::span<const Choice<const char*>>(scenes), "scene", "the glass object");
    cli::number(app, "--size", o.size, 1, 1 << 14, "rays per image side");
    cli::number(app, "--tile", o.tile, 1, 1 << 14, "tile side in rays");
    cli::number(app, "--passes", o.passes, 1, 1 << 10, "refracted passes");
    cli::number(app, "--reps", o.reps, 1, 1 << 10, "timed repetitions (the best is kept)");
    cli::numbers(app, "--counts", o.counts, 10, 1 << 24, "triangle counts of the glass object");
    cli::parse_or_exit(app, argc, argv, "bench_cones");
    if (o.plot.empty() && !o.csv.empty()) {
        const std::size_t dot = o.csv.rfind('.');
        o.plot = (dot == std::string::npos ? o.csv : o.csv.substr(0, dot)) + ".png";
    }
}

/// Best of `reps` runs of the passes from `start`; the rays after the last run are left in
/// `out`.
template <class Run>
double time_passes(const std::vector<Ray<float>>& start, int reps, std::vector<Ray<float>>& out, PassStats& stats,
                   Run&& run) {
    double best = infinity<double>;
    for (int r = 0; r < reps; ++r) {
        out = start;
        const auto t0 = std::chrono::steady_clock::now();
        stats = run(std::span<Ray<float>>(out));
        best = std::min(best, seconds_since(t0));
    }
    return best;
}

std::size_t differing(const std::vector<Ray<float>>& a, const std::vector<Ray<float>>& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(Ray<float>)) != 0;
    return n;
}

void write_plot(const Options& o) {
    if (o.csv.empty() || std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
        if (!o.csv.empty()) std::printf("# gnuplot not found: no plot\n");
        return;
    }
    const std::string script = o.plot + ".gp";
    FILE* f = std::fopen(script.c_str(), "w");
    if (!f) return;
    std::fprintf(f,
                 "set terminal png size 1100,460\nset output '%s'\nset datafile separator ','\n"
                 "set multiplot layout 1,2 title 'hierarchical ray engine (000 ch. 6): refracted passes, %dx%d rays, "
                 "%dx%d tiles'\n"
                 "set termoption noenhanced\nset logscale xy\nset grid\nset key top left\nset xlabel 'triangles'\n"
                 "set xrange [50:100000]\nmethods = 'brute tiles tiles_split tree'\n"
                 "rows(m) = sprintf(\"< grep ',%%s,' '%s'\", m)\n"
                 "set ylabel 'seconds (refracted passes)'\n"
                 "plot for [m in methods] rows(m) using 1:3 with linespoints lw 2 title m\n"
                 "set ylabel 'ray-triangle tests per ray segment'\n"
                 "plot for [m in methods] rows(m) using 1:4 with linespoints lw 2 title m\n"
                 "unset multiplot\n",
                 o.plot.c_str(), o.size, o.size, o.tile, o.tile, o.csv.c_str());
    std::fclose(f);
    if (std::system(("gnuplot '" + script + "'").c_str()) == 0) std::printf("# plot: %s\n", o.plot.c_str());
    std::remove(script.c_str());
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    parse(argc, argv, o);
    const TileGrid grid(o.size, o.size, o.tile);
    std::vector<Row> rows;
    std::printf("# bench_cones: %d x %d rays, %d x %d tiles, up to %d refracted passes, best of %d\n", o.size, o.size,
                o.tile, o.tile, o.passes, o.reps);
    std::printf("%9s %11s %10s %9s %12s %9s %6s\n", "triangles", "method", "seconds", "tests/ray", "segments",
                "x brute", "same");
    bool all_same = true;
    for (const int target : o.counts) {
        const Mesh<float> mesh = object_with(o.scene, target);
        const std::span<const TriangleVertices<float>> tris(mesh);
        const int n = int(mesh.size());
        const AABB<float> box = mesh_bounds(tris);
        const GlassShader<float> glass(tris, 1.5f, 1e-4f * glm::length(box.extent()));

        // Setup (untimed): the primary refracted rays, as 000's rasterization pass makes them.
        auto t0 = std::chrono::steady_clock::now();
        const Tree tree(tris, {.threads = 1});
        const double tree_build = seconds_since(t0);
        t0 = std::chrono::steady_clock::now();
        const RayTileEngine<Ivm<float>> engine(tris, TileOptions::fixed());  // 000's two levels
        const RayTileEngine<Ivm<float>> split(tris, TileOptions{});           // adaptive split
        const double engine_setup = seconds_since(t0);
        const BruteForce<Ivm<float>> brute(tris);
        std::vector<Ray<float>> start = camera_rays(box, o.size);
        TileWorkspace<float> ws;
        {
            const PassStats p = trace_passes(tree, std::span<Ray<float>>(start), 1, glass, ws);
            // Rays that missed the object end: the engine skips them (000's stencil flags).
            for (std::size_t i = 0; i < start.size(); ++i)
                if (!ws.active[i]) start[i].direction = Vec3f(0), start[i].origin = Vec3f(0);
            std::printf("# %d triangles: %llu of %zu primary rays hit the glass; tree build %.4f s, engine setup %.4f s\n",
                        n, (unsigned long long)p.hits, start.size(), tree_build, engine_setup);
        }
        auto stop_missed = [&](std::size_t i, Ray<float>& r, const StoreHit<float>& h, bool f) { return glass(i, r, h, f); };

        std::vector<Ray<float>> out_brute, out_tiles, out_tree;
        PassStats sb, st, sk;
        // Brute force is slow at high counts: fewer repetitions there (it dominates the run).
        const int brute_reps = n > 10000 ? 1 : o.reps;
        const double tb = time_passes(start, brute_reps, out_brute, sb, [&](std::span<Ray<float>> r) {
            return trace_passes(brute, r, o.passes, stop_missed, ws);
        });
        sb.tests = sb.rays * std::uint64_t(n);
        const double tt = time_passes(start, o.reps, out_tiles, st, [&](std::span<Ray<float>> r) {
            return engine.trace_passes(r, grid, o.passes, stop_missed, ws);
        });
        std::vector<Ray<float>> out_split;
        PassStats ss;
        const double ts = time_passes(start, o.reps, out_split, ss, [&](std::span<Ray<float>> r) {
            return split.trace_passes(r, grid, o.passes, stop_missed, ws);
        });
        const double tk = time_passes(start, o.reps, out_tree, sk, [&](std::span<Ray<float>> r) {
            return trace_passes(tree, r, o.passes, stop_missed, ws);
        });
        {  // the tree's tests, counted in an untimed run
            const CountingTree counting(tris, {.threads = 1});
            std::vector<Ray<float>> tmp = start;
            counted_tests = 0;
            const PassStats c = trace_passes(counting, std::span<Ray<float>>(tmp), o.passes, stop_missed, ws);
            sk.tests = counted_tests;
            sk.rays = c.rays;
        }
        struct Result {
            const char* name;
            double seconds;
            const PassStats* stats;
            std::size_t diff;  // final rays that differ from brute force's
        };
        const Result results[] = {{"brute", tb, &sb, 0},
                                  {"tiles", tt, &st, differing(out_brute, out_tiles)},
                                  {"tiles_split", ts, &ss, differing(out_brute, out_split)},
                                  {"tree", tk, &sk, differing(out_brute, out_tree)}};
        all_same &= results[1].diff == 0 && results[2].diff == 0;
        for (const Result& r : results) {
            std::printf("%9d %11s %10.5f %9.1f %12llu %9.2f %6s\n", n, r.name, r.seconds, r.stats->tests_per_ray(),
                        (unsigned long long)r.stats->rays, tb / r.seconds,
                        r.diff == 0 ? "yes" : std::to_string(r.diff).c_str());
            rows.push_back({n, r.name, r.seconds, r.stats->tests_per_ray()});
        }
        std::printf("# %d triangles: tiles %.2fx brute, tiles_split %.2fx brute, tree %.2fx brute, tree %.2fx tiles; "
                    "%llu of %llu tiles fell back to the all-admitting cone\n",
                    n, tb / tt, tb / ts, tb / tk, tt / tk, (unsigned long long)st.tiles_all, (unsigned long long)st.tiles);
        std::printf("# %d triangles, dynamic geometry (tree rebuilt every frame): tree build + passes %.4f s; tiles take "
                    "%.2fx that, tiles_split %.2fx (above 1: the tree wins even with its build)\n",
                    n, tree_build + tk, tt / (tree_build + tk), ts / (tree_build + tk));
        std::fflush(stdout);
    }

    // Where the tree overtakes the tiles: first count with tree faster, interpolated in log-log.
    std::vector<std::pair<double, double>> ratio;  // (triangles, tiles seconds / tree seconds)
    for (std::size_t i = 0; i + 3 < rows.size(); i += 4) ratio.push_back({double(rows[i].triangles), rows[i + 1].seconds / rows[i + 3].seconds});
    bool found = false;
    for (std::size_t i = 0; i < ratio.size() && !found; ++i) {
        if (ratio[i].second < 1.0) continue;
        found = true;
        if (i == 0) {
            std::printf("# the tree is already faster than the tiles at %.0f triangles (%.2fx)\n", ratio[0].first,
                        ratio[0].second);
        } else {
            const double l0 = std::log(ratio[i - 1].first), l1 = std::log(ratio[i].first);
            const double r0 = std::log(ratio[i - 1].second), r1 = std::log(ratio[i].second);
            const double cross = std::exp(l0 + (l1 - l0) * (0 - r0) / (r1 - r0));
            std::printf("# the tree overtakes the tiles between %.0f and %.0f triangles (about %.0f, log-log "
                        "interpolation of tiles/tree time)\n",
                        ratio[i - 1].first, ratio[i].first, cross);
        }
    }
    if (!found) std::printf("# the tiles are faster than the tree at every count measured\n");
    std::printf("# tiles' final rays bit-identical to brute force at every count: %s\n", all_same ? "yes" : "NO");

    if (!o.csv.empty()) {
        FILE* f = std::fopen(o.csv.c_str(), "w");
        if (!f) {
            std::fprintf(stderr, "bench_cones: cannot write %s\n", o.csv.c_str());
            return 1;
        }
        std::fprintf(f, "triangles,method,seconds,tests_per_ray\n");
        for (const Row& r : rows) std::fprintf(f, "%d,%s,%.6g,%.6g\n", r.triangles, r.method.c_str(), r.seconds, r.tests_per_ray);
        std::fclose(f);
        std::printf("# csv: %s\n", o.csv.c_str());
        write_plot(o);
    }
    return all_same ? 0 : 1;
}
