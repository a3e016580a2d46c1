// bench_grids: Szécsi 2009, §4.2's claim that a kd-tree needs 2-3x fewer ray-triangle tests
// than a uniform grid or an octree, measured on the shared meshes, single thread.
//
//   bench_grids [--scenes DIR] [--only STEM] [--rays N] [--primary N] [--reps N] [--quick]
//               [--no-generated] [--grid-density X] [--octree-leaf N] [--octree-depth N]
//
// For every .obj of --scenes (default: ../shared/scenes beside the repository) and, reported
// apart, the generated torus knot: incoherent rays (--rays, default 200000) and primary rays
// (--primary N: N x N, default 384), made as bench_trees makes them (tests/support/
// tree_scenes.hpp). Five accelerators, all with Möller-Trumbore records:
//   grid       trees/uniform_grid.hpp, about --grid-density (4) cells per triangle, triangles
//              binned by an exact triangle-box test; one scalar test per referenced triangle
//              (tests/support/cell_leaves.hpp's leaf callable);
//   octree     trees/octree.hpp, leaves of at most --octree-leaf (8) triangles, depth at most
//              --octree-depth (10); the same leaf callable;
//   kd-classic KdTree<float, MollerTrumbore<float>, PointerLayout> with the classic SAH
//              constants K_T = 1, K_I = 4/3 (Wald and Havran 2006's K_T = 15, K_I = 20) and an
//              empty-space bonus of 0.2;
//   kd         the same tree with glint's defaults (K_I = 0.07: leaves are tested 8 at a time);
//   bvh8       MeshBvh<MollerTrumbore<float>, 8> (glint's default tree).
// Per ray: triangle tests (padding lanes of the trees' batches of 8 not counted; "lanes"
// counts them), steps (grid: cells visited; octree: nodes visited; bvh8: inner nodes whose
// children were tested; kd: not counted, its traversal has no hook), hits. Time: --reps
// passes (default 5) of every accelerator, the order rotating each pass; Mrays/s from the
// median pass, speed ratios the median over passes of the ratio of adjacent passes.
// --quick: the torus knot only, 2000 rays, 32 x 32 primary rays, one pass (the CI smoke run).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/io/obj.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/trees/octree.hpp>
#include <glint/trees/traversal.hpp>
#include <glint/trees/uniform_grid.hpp>

#include "cell_leaves.hpp"
#include "flags.hpp"  // cli/: the command-line conventions
#include "tree_scenes.hpp"

using namespace glint;

namespace {

using MT = MollerTrumbore<float>;
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Options {
    std::string scenes = GLINT_BENCH_SCENES, only;
    std::size_t rays = 200'000;
    int primary = 384, reps = 5;
    bool quick = false, no_generated = false;
    UniformGridOptions grid{};
    OctreeOptions octree{};
};

/// What one accelerator did on one ray set, summed over its rays.
struct Counts {
    std::uint64_t tests = 0, lanes = 0, steps = 0, hits = 0;
    bool has_steps = true;
};

/// One accelerator as the benchmark drives it: a timed pass and a counted pass over a ray set.
class Runner {
public:
    virtual ~Runner() = default;
    /// Seconds of one closest-hit pass over `rays`.
    virtual double pass(const std::vector<Ray<float>>& rays) const = 0;
    /// The counts of a closest-hit pass; t[i] = ray i's hit t (+inf: a miss).
    virtual Counts count(const std::vector<Ray<float>>& rays, std::vector<float>& t) const = 0;
    std::string name;
    double build_s = 0;
};

/// Times `closest(ray, hit)` over the rays (its hit count is kept so the loop stays).
template <class Closest>
double time_pass(const std::vector<Ray<float>>& rays, Closest&& closest) {
    std::size_t hits = 0;
    const auto t0 = Clock::now();
    for (const auto& r : rays) {
        StoreHit<float> h;
        hits += closest(r, h);
    }
    const double s = seconds_since(t0);
    if (hits == std::size_t(-1)) std::puts("");
    return s;
}

/// The grid or the octree (Cells = UniformGrid<float> or Octree<float>) over the leaf callable.
template <class Cells, class CellOptions>
class CellRunner : public Runner {
public:
    CellRunner(const char* label, const Mesh<float>& m, const CellOptions& opt) : tris_(m) {
        name = label;
        const auto t0 = Clock::now();
        leaves_ = std::make_unique<TriangleCells>(tris_);
        cells_ = Cells(leaves_->boxes(), opt, leaves_->overlap_test());
        build_s = seconds_since(t0);
    }
    double pass(const std::vector<Ray<float>>& rays) const override {
        return time_pass(rays, [&](const Ray<float>& r, StoreHit<float>& h) { return leaves_->closest_hit(cells_, r, h); });
    }
    Counts count(const std::vector<Ray<float>>& rays, std::vector<float>& t) const override {
        Counts c;
        t.assign(rays.size(), infinity<float>);
        for (std::size_t i = 0; i < rays.size(); ++i) {
            StoreHit<float> h;
            c.hits += leaves_->closest_hit(cells_, rays[i], h, [&] { ++c.tests; }, [&] { ++c.steps; });
            t[i] = h.t;
        }
        c.lanes = c.tests;
        return c;
    }
    const Cells& cells() const { return cells_; }

private:
    Mesh<float> tris_;
    std::unique_ptr<TriangleCells> leaves_;
    Cells cells_;
};

/// A tree whose leaves are TriangleLeaves<MT> (kd-tree or MeshBvh); `traverse(r, leaf, hook)`
/// runs its traversal with a leaf callable.
template <class Tree>
class TreeRunner : public Runner {
public:
    template <class Build>
    TreeRunner(const char* label, Build&& build) {
        name = label;
        const auto t0 = Clock::now();
        tree_ = build();
        build_s = seconds_since(t0);
    }
    double pass(const std::vector<Ray<float>>& rays) const override {
        return time_pass(rays, [&](const Ray<float>& r, StoreHit<float>& h) { return tree_->closest_hit(r, h); });
    }
    Counts count(const std::vector<Ray<float>>& rays, std::vector<float>& t) const override {
        Counts c;
        t.assign(rays.size(), infinity<float>);
        const auto& store = tree_->leaves().store();
        for (std::size_t i = 0; i < rays.size(); ++i) {
            Ray<float> r = rays[i];
            StoreHit<float> h;
            const auto world = tree_->leaves().prepare(r);
            LeafQuery<MT, false> leaf(tree_->leaves(), r, world, h);
            auto counted = [&](std::uint32_t first, std::uint32_t n) {  // Möller-Trumbore: n padded records
                c.lanes += n;
                for (std::uint32_t k = first; k < first + n; ++k) c.tests += store.id(k) != ~0u;
                return leaf(first, n);
            };
            if (traverse(r, counted, c)) t[i] = h.t, ++c.hits;
        }
        return c;
    }

private:
    template <class Leaf>
    bool traverse(Ray<float>& r, Leaf& leaf, Counts& c) const {
        if constexpr (requires { tree_->bvh(); }) {
            return tree_->bvh().template intersect<false>(r, leaf, [&] { ++c.steps; });
        } else {
            c.has_steps = false;  // the kd-tree's traversal has no node hook
            return tree_->template intersect<false>(r, leaf);
        }
    }
    std::unique_ptr<Tree> tree_;
};

struct Scene {
    std::string name;
    Mesh<float> mesh;
    bool generated = false;
};

/// One accelerator's numbers on one ray set of one scene.
struct Row {
    std::string scene, set, accel;
    bool generated = false;
    std::size_t rays = 0;
    Counts counts;
    double mrays = 0, build_s = 0;
    std::vector<double> seconds;  // per pass
    std::size_t disagree = 0;     // rays whose hit t differs from kd's (beyond 1e-4 relative)
};

/// Median of v (sorted copy).
double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

/// The five accelerators over mesh m.
std::vector<std::unique_ptr<Runner>> make_runners(const Mesh<float>& m, const Options& opt) {
    using Kd = KdTree<float, MT, PointerLayout>;
    std::vector<std::unique_ptr<Runner>> v;
    v.push_back(std::make_unique<CellRunner<UniformGrid<float>, UniformGridOptions>>("grid", m, opt.grid));
    v.push_back(std::make_unique<CellRunner<Octree<float>, OctreeOptions>>("octree", m, opt.octree));
    const KdBuildOptions classic{.traversal_cost = 1.0, .intersection_cost = 20.0 / 15.0, .empty_bonus = 0.2};
    v.push_back(std::make_unique<TreeRunner<Kd>>("kd-classic", [&] { return std::make_unique<Kd>(m, KdTreeBuilder<float>{classic}); }));
    v.push_back(std::make_unique<TreeRunner<Kd>>("kd", [&] { return std::make_unique<Kd>(m); }));
    v.push_back(std::make_unique<TreeRunner<MeshBvh<MT, 8>>>("bvh8", [&] {
        return std::make_unique<MeshBvh<MT, 8>>(std::span<const TriangleVertices<float>>(m), BvhBuildOptions{.threads = 1});
    }));
    return v;
}

/// Counts and times every runner on one ray set; appends one row per runner.
void run_set(const Scene& sc, const std::string& set, const std::vector<Ray<float>>& rays,
             const std::vector<std::unique_ptr<Runner>>& runners, const Options& opt, std::vector<Row>& rows) {
    const std::size_t n = runners.size(), first = rows.size();
    std::vector<std::vector<float>> t(n);
    for (std::size_t a = 0; a < n; ++a)
        rows.push_back({sc.name, set, runners[a]->name, sc.generated, rays.size(), runners[a]->count(rays, t[a]), 0,
                        runners[a]->build_s, {}, 0});
    for (int rep = 0; rep < opt.reps; ++rep)
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t a = (k + std::size_t(rep)) % n;  // the order rotates each pass
            rows[first + a].seconds.push_back(runners[a]->pass(rays));
        }
    const std::size_t ref = 3;  // kd: the hits every other accelerator is compared with
    for (std::size_t a = 0; a < n; ++a) {
        Row& row = rows[first + a];
        row.mrays = double(rays.size()) / median(row.seconds) * 1e-6;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            const float x = t[a][i], y = t[ref][i];
            row.disagree += std::isinf(x) != std::isinf(y) || std::abs(x - y) > 1e-4f * std::max(1.0f, std::abs(y));
        }
        const double per = 1.0 / double(rays.size());
        std::printf("%-16s %-10s %-10s build %8.4f s  tests %7.2f  lanes %7.2f  steps ", sc.name.c_str(), set.c_str(),
                    row.accel.c_str(), row.build_s, double(row.counts.tests) * per, double(row.counts.lanes) * per);
        if (row.counts.has_steps) std::printf("%7.2f", double(row.counts.steps) * per);
        else std::printf("%7s", "-");
        std::printf("  %7.3f Mrays/s  hits %zu  differ from kd %zu\n", row.mrays, std::size_t(row.counts.hits), row.disagree);
    }
    std::fflush(stdout);
}

/// The row of `accel` among rows[first ...] (same scene and set).
const Row& find(const std::vector<Row>& rows, std::size_t first, const std::string& accel) {
    for (std::size_t i = first; i < rows.size(); ++i)
        if (rows[i].accel == accel) return rows[i];
    throw Error("bench_grids: no row " + accel);
}

/// Median over passes of b's pass time / a's (above 1: a is faster), passes paired by index.
double speed(const Row& a, const Row& b) {
    std::vector<double> r;
    for (std::size_t i = 0; i < a.seconds.size(); ++i) r.push_back(b.seconds[i] / a.seconds[i]);
    return median(r);
}

/// The summary of one ray set: per scene tests per ray and the ratios, then geometric means
/// over the shared meshes (the generated scene apart).
void summary(const std::vector<Row>& rows, const std::string& set) {
    std::printf("\n%s rays: triangle tests per ray, tests ratios and speed ratios (speed: the others' time / grid's or octree's)\n", set.c_str());
    std::puts("| mesh | grid | octree | kd-classic | kd | bvh8 | grid/kd-classic | octree/kd-classic | grid/kd | octree/kd "
              "| speed grid/kd-classic | octree/kd-classic | grid/kd | octree/kd | grid/bvh8 | octree/bvh8 |");
    std::puts("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    std::vector<double> logs(10, 0.0);
    int meshes = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
        if (rows[i].set != set || rows[i].accel != "grid") continue;
        const Row &g = rows[i], &o = find(rows, i, "octree"), &kc = find(rows, i, "kd-classic"), &kd = find(rows, i, "kd"),
                  &bv = find(rows, i, "bvh8");
        const auto per = [](const Row& r) { return double(r.counts.tests) / double(r.rays); };
        const double v[10] = {per(g) / per(kc), per(o) / per(kc), per(g) / per(kd), per(o) / per(kd), speed(g, kc),
                              speed(o, kc),     speed(g, kd),     speed(o, kd),     speed(g, bv), speed(o, bv)};
        std::printf("| %s%s | %.1f | %.1f | %.1f | %.1f | %.1f |", g.scene.c_str(), g.generated ? " (generated)" : "", per(g),
                    per(o), per(kc), per(kd), per(bv));
        for (double x : v) std::printf(" %.2f |", x);
        std::printf("\n");
        if (g.generated) continue;
        ++meshes;
        for (int k = 0; k < 10; ++k) logs[std::size_t(k)] += std::log(v[k]);
    }
    if (meshes == 0) return;
    std::printf("| **geometric mean, %d meshes** | | | | | |", meshes);
    for (double l : logs) std::printf(" **%.2f** |", std::exp(l / meshes));
    std::printf("\n");
}

Options parse(int argc, char** argv) {
    Options o;
    cli::App app("bench_grids: triangle tests per ray and speed of a uniform grid and an octree against kd-trees and "
                 "the 8-wide BVH, single thread");
    cli::text(app, "--scenes", o.scenes, "the folder of OBJ meshes", "DIR");
    cli::text(app, "--only", o.only, "only this mesh (file stem) or the generated torus-knot", "STEM");
    cli::number(app, "--rays", o.rays, std::size_t(1), std::size_t(1) << 30, "incoherent rays per scene");
    cli::number(app, "--primary", o.primary, 1, 8192, "N x N primary rays per scene");
    cli::number(app, "--reps", o.reps, 1, 1000, "timed passes of every accelerator");
    cli::flag(app, "--quick", o.quick, "the torus knot only, 2000 rays, 32 x 32 primary rays, one pass");
    cli::flag(app, "--no-generated", o.no_generated, "leave out the generated torus knot");
    cli::number(app, "--grid-density", o.grid.cells_per_primitive, 1e-3, 1e3, "grid cells per triangle");
    cli::number(app, "--octree-leaf", o.octree.max_leaf, 1u, 1024u, "octree: most triangles in a leaf");
    cli::number(app, "--octree-depth", o.octree.max_depth, 0u, 20u, "octree: deepest level");
    cli::parse_or_exit(app, argc, argv, "bench_grids");
    if (o.quick) o.rays = std::min<std::size_t>(o.rays, 2000), o.primary = std::min(o.primary, 32), o.reps = 1;
    return o;
}

/// The scenes: every .obj of --scenes (sorted by name; none with --quick), then the torus knot.
std::vector<Scene> load_scenes(const Options& opt) {
    std::vector<Scene> scenes;
    if (!opt.quick) {
        if (!std::filesystem::is_directory(opt.scenes)) throw Error("--scenes: no folder '" + opt.scenes + "'");
        std::vector<std::filesystem::path> files;
        for (const auto& e : std::filesystem::directory_iterator(opt.scenes))
            if (e.path().extension() == ".obj" && (opt.only.empty() || e.path().stem() == opt.only)) files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const auto& f : files) scenes.push_back({f.stem().string(), load_obj(f.string()).triangles, false});
    }
    if (!opt.no_generated && (opt.only.empty() || opt.only == "torus-knot"))
        scenes.push_back({"torus-knot", make_torus_knot<float>(), true});
    if (scenes.empty()) throw Error("no scene to run (--scenes '" + opt.scenes + "', --only '" + opt.only + "')");
    return scenes;
}

}  // namespace

int main(int argc, char** argv) try {
    const Options opt = parse(argc, argv);
    std::vector<Row> rows;
    for (const Scene& sc : load_scenes(opt)) {
        const auto runners = make_runners(sc.mesh, opt);
        const auto& grid = static_cast<const CellRunner<UniformGrid<float>, UniformGridOptions>&>(*runners[0]).cells();
        const auto& oct = static_cast<const CellRunner<Octree<float>, OctreeOptions>&>(*runners[1]).cells();
        const auto res = grid.resolution();
        std::printf("# %s: %zu triangles; grid %ux%ux%u (%.2f references per triangle); octree %zu nodes (%.2f references "
                    "per triangle)\n",
                    sc.name.c_str(), sc.mesh.size(), res[0], res[1], res[2], double(grid.prims().size()) / double(sc.mesh.size()),
                    oct.nodes().size(), double(oct.prims().size()) / double(sc.mesh.size()));
        run_set(sc, "incoherent", make_incoherent_rays<float>(sc.mesh, opt.rays), runners, opt, rows);
        run_set(sc, "primary", make_primary_rays<float>(sc.mesh, opt.primary, opt.primary), runners, opt, rows);
    }
    summary(rows, "incoherent");
    summary(rows, "primary");
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_grids: %s\n", e.what());
    return 1;
}
