// bench_cuts: the VPL integrator gathering through light cuts (lights/cuts.hpp; Fernandez 2004,
// §5.2, as lightcuts over the virtual lights) against gathering every VPL, on the Cornell box
// and the bunny in it, with 10^4 and 10^5 VPLs; and the cluster tree's build time and memory
// at 10^3, 10^4 and 10^5 lights.
//
// Each row renders the VPL part only (VplSettings::direct = false; one ray per pixel centre,
// single thread), timed from the integrator's construction (the tree's build included) to the
// image; every-VPL and cut renders alternate, and each time is the best of --reps (the gather
// alone: the cut's time less the best of --reps separate builds of its tree). Errors are
// against the every-VPL image of the same VPLs: E = mean over pixels of
// min(|L_cut - L| / L, 1) on luminance (Fernandez 2004, eq. 4.3; a pixel with L = 0 counts 0
// if the cut gives 0 too, else 1), rmse = sqrt(sum (L_cut - L)^2 / sum L^2) over the pixels'
// RGB (relative RMSE). lights_per_pixel is the VPL count (every VPL) or the mean cut size;
// shadow_rays_per_pixel counts the visibility tests. Pin it: taskset -c 1 build/benchmarks/bench_cuts.
//
//   bench_cuts [--quick] [--size N] [--vpls 10000,100000] [--thresholds 0.02,0.01,0.005]
//              [--max-nodes 300] [--reps R] [--mesh FILE.obj] [--csv FILE] [--tree-csv FILE]
//              [--spatial-tree]
// The method column names the cut as cuts-THRESHOLD-MAXNODES. The cluster trees group the
// VPLs by orientation (VplSettings::grouping's default); --spatial-tree builds Fernandez 2004's.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <glint/core/random.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/io/obj.hpp>
#include <glint/lights/cluster_tree.hpp>
#include <glint/lights/cuts.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/vpl/integrator.hpp>
#include "counted_visibility.hpp"
#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

using Accel = MeshBvh<MollerTrumbore<float>, 8>;
using Img = std::vector<Rgb<float>>;

struct Config {
    int size = 48, reps = 1, max_nodes = 300;
    std::vector<std::size_t> vpls{10000, 100000}, tree_sizes{1000, 10000, 100000};
    std::vector<double> thresholds{0.02, 0.01, 0.005};
    std::string mesh = "../shared/scenes/bunny.obj", csv, tree_csv;
    bool spatial_tree = false;
};

using CountedRays = CountedVisibility<ShadowRayVisibility<Accel>>;

struct Run {
    Img image;
    double seconds = 1e30;
    std::uint64_t rays = 0;
};

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

Config parse(int argc, char** argv) {
    Config c;
    cli::App app("bench_cuts: the VPL integrator's gather through light cuts against every VPL, single thread");
    // --quick first: the flags after it in this list (any given with it) override its sizes.
    app.flag("--quick", [&c] { c.size = 12, c.vpls = {2000}, c.tree_sizes = {1000, 10000}, c.thresholds = {0.02}; },
             "a smoke run: 12 x 12, 2000 VPLs, threshold 0.02");
    cli::number(app, "--size", c.size, 1, 4096, "image width and height");
    cli::number(app, "--reps", c.reps, 1, 100, "timed repetitions");
    cli::number(app, "--max-nodes", c.max_nodes, 0, 1 << 30, "largest cut (0: unlimited)");
    cli::numbers(app, "--vpls", c.vpls, std::size_t(1), std::size_t(1) << 28, "VPL counts");
    cli::numbers(app, "--tree-sizes", c.tree_sizes, std::size_t(1), std::size_t(1) << 28, "lights of the tree build rows");
    cli::numbers(app, "--thresholds", c.thresholds, 0.0, 1.0, "cut thresholds");
    cli::text(app, "--mesh", c.mesh, "FILE.obj: the bunny row's mesh");
    cli::flag(app, "--spatial-tree", c.spatial_tree, "cluster trees in Fernandez 2004's spatial merge order (default: by orientation)");
    cli::output(app, "--csv", c.csv, "write the rows as CSV");
    cli::output(app, "--tree-csv", c.tree_csv, "write the tree build rows as CSV");
    if (!cli::parse(app, argc, argv)) std::exit(0);
    return c;
}

/// VPLs from enough shooting walks for about `target` of them (a pilot of 512 walks gives the
/// VPLs per walk).
std::vector<Vpl<float>> shoot(const Scene<float>& s, const Accel& accel, std::size_t target) {
    const auto roulette = Roulette<float, 3>::classic();
    const double per_walk = double(shoot_scene_vpls(s, accel, roulette, 512, 99).size()) / 512.0;
    const auto walks = std::size_t(std::max(1.0, std::round(double(target) / std::max(per_walk, 1e-3))));
    return shoot_scene_vpls(s, accel, roulette, walks, 1);
}

RenderSettings centres(int size) {
    RenderSettings image;
    image.width = image.height = size;
    image.spp = 1;
    image.pixel_jitter = false;
    image.threads = 1;
    return image;
}

/// One render of the VPL part, timed from the integrator's construction (the cut's tree
/// build included); the best time of the runs so far is kept in `best`.
void render(const Scene<float>& s, const Accel& accel, std::span<const Vpl<float>> vpls, const RenderSettings& image,
            VplSettings st, Run& best) {
    st.direct = false;
    std::uint64_t rays = 0;
    const CountedRays vis{ShadowRayVisibility<Accel>(accel, 1e-4f), &rays};
    const double t0 = now();
    const VplResult r = render_vpls(s, accel, vpls, vis, image, st);
    best.seconds = std::min(best.seconds, now() - t0);
    best.image.assign(r.indirect.pixels.begin(), r.indirect.pixels.end());
    best.rays = rays;
}

/// The mean number of nodes of the cuts at the pixel centres (an untimed pass).
double mean_cut_size(const Scene<float>& s, const Accel& accel, std::span<const Vpl<float>> vpls, const RenderSettings& image,
                     const VplSettings& st) {
    const auto points = primary_points(s, accel, image, st);
    const VplLights<float> lights(vpls, st);
    ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    const float d2min = float(st.min_distance * st.min_distance);
    double nodes = 0;
    for (const PixelPoint<float>& p : points) {
        if (!p.hit) continue;
        const Frame<float> frame = Frame<float>::from_normal(p.n);
        const SurfaceBrdf<float> brdf(s.materials[p.material], frame.to_local(p.wo));
        vis.set_point(p.x, p.n);
        const CutReceiver<float> r{p.x, p.n, frame, &brdf, d2min};
        nodes += evaluate_cut(*lights.tree(), r, st.cut, [&](const PointLight<float>& l) { return vis.visible(l.position); }).nodes;
    }
    return nodes / double(points.size());
}

/// Fernandez 2004, eq. 4.3's E on luminance, and the relative RMSE over RGB.
void errors(const Img& img, const Img& ref, double& E, double& rmse) {
    double e = 0, num = 0, den = 0;
    for (std::size_t i = 0; i < ref.size(); ++i) {
        const double L = ref[i].luminance(), Lc = img[i].luminance();
        e += L > 0 ? std::min(std::abs(Lc - L) / L, 1.0) : (Lc == 0 ? 0.0 : 1.0);
        for (std::size_t c = 0; c < 3; ++c) {
            num += (double(img[i][c]) - ref[i][c]) * (double(img[i][c]) - ref[i][c]);
            den += double(ref[i][c]) * ref[i][c];
        }
    }
    E = e / double(ref.size());
    rmse = den > 0 ? std::sqrt(num / den) : 0.0;
}

/// Build time (best of 3) and bytes per light of the tree over n VPL-like lights (cosine
/// points at random in a unit cube, random normals, fixed seed).
void tree_rows(const Config& c, std::ostringstream& csv) {
    std::printf("cluster tree build (single thread):\n%10s %12s %16s\n", "lights", "seconds", "bytes/light");
    for (std::size_t n : c.tree_sizes) {
        Pcg32 rng(n, 7);
        std::vector<PointLight<float>> lights;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3<float> p(rng.uniform<float>(), rng.uniform<float>(), rng.uniform<float>());
            const Vec3<float> a = square_to_uniform_sphere(Vec2<float>(rng.uniform<float>(), rng.uniform<float>()));
            lights.push_back(PointLight<float>::oriented(p, a, Rgb<float>(rng.uniform<float>() + 0.1f)));
        }
        double best = 1e30, bytes = 0;
        for (int k = 0; k < 3; ++k) {
            const LightClusterTree<float> t(lights);
            best = std::min(best, t.build_seconds());
            bytes = double(t.bytes()) / double(n);
        }
        std::printf("%10zu %12.4f %16.1f\n", n, best, bytes);
        csv << n << ',' << best << ',' << bytes << '\n';
    }
}

Scene<float> bench_scene(const std::string& name, const std::string& mesh) {
    Scene<float> s = builtin_scene<float>("cornell");
    if (name == "bunny") {
        insert_mesh<float>(s, load_obj(mesh).triangles, Material<float>::lambertian(Rgb<float>(0.725f, 0.71f, 0.68f)),
                           cornell_mesh_placement<float>());
        s.name = "bunny";
    }
    return s;
}

VplSettings cut_settings(const Config& c, std::size_t k) {
    return VplSettings{.gather = VplGather::cuts,
                       .cut = {.threshold = c.thresholds[k], .max_nodes = c.max_nodes},
                       .grouping = c.spatial_tree ? ClusterGrouping::spatial : ClusterGrouping::by_orientation};
}

/// The rows of one scene and VPL count: every VPL, then the cut at each threshold, alternating.
void scene_rows(const Config& c, const std::string& name, const Scene<float>& s, const Accel& accel, std::size_t target,
                std::ostringstream& csv) {
    const auto vpls = shoot(s, accel, target);
    const std::span<const Vpl<float>> vs(vpls);
    const RenderSettings image = centres(c.size);
    const double px = double(c.size) * c.size;
    Run all;
    std::vector<Run> cuts(c.thresholds.size());
    for (int rep = 0; rep < c.reps; ++rep) {
        render(s, accel, vs, image, VplSettings{}, all);
        for (std::size_t k = 0; k < cuts.size(); ++k) render(s, accel, vs, image, cut_settings(c, k), cuts[k]);
    }
    csv << name << ",all," << vpls.size() << ',' << vpls.size() << ',' << double(all.rays) / px << ',' << all.seconds << ",0,0\n";
    double build = 1e30;  // the best of as many builds as timed renders
    for (int rep = 0; rep < c.reps; ++rep) build = std::min(build, VplLights<float>(vs, cut_settings(c, 0)).tree()->build_seconds());
    std::printf("%-8s %7zu VPLs  all          %8.3f s  %8.1f rays/px  (the cuts' times include %.3f s of tree build)\n",
                name.c_str(), vpls.size(), all.seconds, double(all.rays) / px, build);
    for (std::size_t k = 0; k < cuts.size(); ++k) {
        double E, rmse;
        errors(cuts[k].image, all.image, E, rmse);
        const VplSettings st = cut_settings(c, k);
        const double nodes = mean_cut_size(s, accel, vs, image, st);
 csv << name << ",cuts-" << c.thresholds[k] << '-' << c.max_nodes << ',' << vpls.size() << ',' << nodes << ',' << double(cuts[k].rays) / px << ','
            << cuts[k].seconds << ',' << E << ',' << rmse << '\n';
        std::printf("%-8s %7zu VPLs  cuts %-6g  %8.3f s  %8.1f rays/px  %6.1f nodes/px  E %.4f  rel. RMSE %.4f  speedup %.1fx"
                    " (the gather alone, without the build: %.1fx)\n",
                    name.c_str(), vpls.size(), c.thresholds[k], cuts[k].seconds, double(cuts[k].rays) / px, nodes, E, rmse,
                    all.seconds / cuts[k].seconds, all.seconds / std::max(cuts[k].seconds - build, 1e-9));
    }
}

}  // namespace

int main(int argc, char** argv) try {
    const Config c = parse(argc, argv);
    std::ostringstream trees, rows;
    tree_rows(c, trees);
    for (const std::string name : {"cornell", "bunny"}) {
        const Scene<float> s = bench_scene(name, c.mesh);
        const Accel accel(s.triangles);
        for (std::size_t n : c.vpls) scene_rows(c, name, s, accel, n, rows);
    }
    const auto write = [](const std::string& path, const std::string& header, const std::string& body) {
        if (path.empty()) return;
        std::ofstream out(path);
        if (!out) throw Error("bench_cuts: cannot write '" + path + "'");
        out << header << body;
    };
    write(c.csv, "scene,method,lights,lights_per_pixel,shadow_rays_per_pixel,seconds,error_E,rmse\n", rows.str());
    write(c.tree_csv, "lights,seconds,bytes_per_light\n", trees.str());
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_cuts: %s\n", e.what());
    return 1;
}
