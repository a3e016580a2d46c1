// bench_convergence: error against time for the path tracer's policies, and Szécsi 2009's claims as
// efficiency ratios measured in one run.
//
//   ./build/benchmarks/bench_convergence --scene all --csv convergence.csv
//   ./build/benchmarks/bench_convergence --scene arealight --csv arealight.csv --size 64 --max-spp 64
//   ./build/benchmarks/bench_convergence --scene all --sampler halton --csv convergence_halton.csv
//
// For each scene, each method renders at spp = 1, 2, 4, ... max-spp; the RMSE over the image
// is measured against the exact answer (furnace: 1 everywhere) or against a reference render
// (16x max-spp, another seed, cached as EXR with its variance layer in --cache DIR; the
// reference's own variance is subtracted from the measured MSE).
//
// What is measured is light transport's error: camera rays go through pixel centres, in the
// methods' images and in the reference alike (RenderSettings::pixel_jitter off). With rays
// jittered over each pixel (--jitter), the error also holds the pixel-footprint noise at
// silhouettes and at the light's edges, which no method here changes: on the 96x96 Cornell box
// 1% of the pixels (the light's edges) then hold 92% of the image's variance, and termination
// adds 7% of classic roulette's MSE instead of 76%, so every roulette ratio is pulled to 1.
// --sampler halton runs every method on Halton walks (random digit permutations; halton-owen: Owen scrambling) instead of PCG random
// numbers (spectral roulette gains more there: the first bounce's termination is stratified
// for both methods, and what is left is the deeper termination the spectral rule improves).
//
// Efficiency is
// 1 / (MSE * seconds); a method's ratio to its baseline is the geometric mean over the spp
// levels >= 4 of the ratio at equal spp. Methods per scene:
//   furnace         roulette: classic (Szécsi 2009's baseline), spectral, estimate, spectral+estimate,
//                   throughput (the field's baseline: pbrt-v4, Mitsuba 3, Cycles), Szécsi 2009's ideas on
//                   it (throughput+spectral, throughput+estimate, throughput+spectral+estimate),
//                   none (no roulette, throughput cut-off); each with its efficiency against
//                   classic and against throughput
//   cornell         roulette: as furnace
//   cornell-glossy  BRDF selection: mis (baseline), dis, w
//   arealight       direct lighting, 10 light samples: importance (baseline), correlated, combined
//                   (direct illumination only, max depth 1, as Szécsi 2009, §3.2 compares it:
//                   with indirect light the shared path-tracing noise would hide the
//                   difference)
//   envmap          environment lighting (Szécsi 2009, §3.3), at the first vertex only, single
//                   thread: importance (MisEnvironment, the baseline), and CorrelatedEnvironment
//                   with K = --light-samples (default 16) map-importance samples per vertex:
//                   importance-k (lambda = 0), correlated (eq. 3.5), combined-3.5, combined (both
//                   main parts chosen per cell); not part of --scene all
//   ./build/benchmarks/bench_convergence --scene envmap --size 48 --max-spp 64 --csv envmap.csv
// --compare roulette runs the roulette methods on any scene (e.g. cornell-glossy); --rr-depth N
// sets the throughput roulettes' first decision depth (default 3).
// --analysis (furnace, cornell) prints instead what bounds the radiance-estimate roulette: the
// goodness d of Szécsi 2009, §2.3 for the closed-scene and the pilot-fitted estimate, the floor no
// estimate can reach below, and the share of the MSE that termination adds at all; on the
// furnace also a geometry-free chain model of the room that predicts what spectral roulette
// can gain over classic there (Szécsi 2009, §2.2). --weights mean|luminance sets the roulettes'
// band weights H (default mean, matching the RMSE's equal weights on R, G, B).
// CSV columns: scene,method,spp,seconds,rmse. A gnuplot plot (RMSE against seconds) is
// written next to the CSV when gnuplot is installed.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <numeric>
#include <utility>
#include <string>
#include <vector>

#include <glint/io/exr.hpp>
#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/correlated_environment.hpp>
#include <glint/tracer/named_render.hpp>
#include "glint_instances.hpp"  // render_named for AnyAccel, compiled once (instances/)
#include <glint/tracer/scenes.hpp>


#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

struct Method {
    std::string name;     // as in the CSV
    NamedRender<float> options;
};

struct Point {
    int spp;
    double seconds, rmse;
};

struct Config {
    std::string scene = "all", csv, cache = "bench_cache", plot;
    std::string direct;  // direct lighting of the roulette and selection scenes (default per scene)
    std::string radiance_estimate = "pilot";  // L~ of the estimate roulettes: pilot | scene
    bool reduce = false;                      // shorten walks by the estimate's goodness
    std::string weights = "mean";             // roulette band weights H: mean | luminance
    std::string sampler = "random";           // random | halton | halton-owen | halton-cp (render()'s names)
    int size = 96, max_spp = 64, threads = 0;
    bool jitter = false;  // --jitter: camera rays jittered over each pixel (default: through its centre)
    int light_samples = 0;   // --light-samples N: light samples per vertex (0: 1; 10 on arealight)
    std::uint64_t seed = 0;  // --seed N: methods render with seed 1000 N + spp (N = 0: seed = spp)
    bool quick = false;
    bool analysis = false;  // --analysis: Szécsi 2009, §2.3's goodness d and termination's share
    std::string compare;    // --compare roulette: the roulette methods on every scene
    int rr_depth = 3;       // --rr-depth N: the throughput roulettes' min_depth
};

/// The roulettes compared: Szécsi 2009's four, the field's throughput rule, Szécsi 2009's ideas on top of it,
/// and no roulette.
const std::vector<std::string>& compared_roulettes() {
    static const std::vector<std::string> v{"classic", "spectral", "estimate", "spectral+estimate", "throughput",
                                            "throughput+spectral", "throughput+estimate",
                                            "throughput+spectral+estimate", "none"};
    return v;
}

std::vector<Method> methods_for(const std::string& scene, const Config& cfg) {
    auto base = [&] {
        NamedRender<float> o;
        o.image.width = o.image.height = cfg.size;
        o.image.threads = cfg.threads;
        o.roulette = "spectral";
        // The furnace is lit by all its walls: a pure random walk collecting emission where
        // it hits (Szécsi 2009, §2.2's setting); the others use light sampling with MIS.
        o.direct = !cfg.direct.empty() ? cfg.direct : scene == "furnace" ? "brdf" : "mis";
        o.weights = cfg.weights;  // default mean: the RMSE weighs R, G and B equally
        o.estimate = cfg.radiance_estimate;
        o.reduce_continuation = cfg.reduce;
        if (cfg.light_samples > 0) o.tracer.light_samples = cfg.light_samples;
        o.image.pixel_jitter = cfg.jitter;
        o.sampler = cfg.sampler;
        o.rr_depth = cfg.rr_depth;
        return o;
    };
    std::vector<Method> m;
    if (scene == "furnace" || scene == "cornell" || cfg.compare == "roulette") {
        for (const std::string& r : compared_roulettes()) {
            NamedRender<float> o = base();
            o.roulette = r;
            m.push_back({r, o});
        }
    } else if (scene == "cornell-glossy") {
        for (const std::string s : {"mis", "dis", "w"}) {
            NamedRender<float> o = base();
            o.selection = s;
            m.push_back({s, o});
        }
    } else if (scene == "arealight") {
        for (const std::string d : {"importance", "correlated", "combined"}) {
            NamedRender<float> o = base();
            o.direct = d;
            o.tracer.light_samples = cfg.light_samples > 0 ? cfg.light_samples : 10;
            o.tracer.max_depth = 1;
            m.push_back({d, o});
        }
    } else {
        throw Error("bench_convergence: no methods for scene '" + scene +
                    "' (furnace, cornell, cornell-glossy, arealight, envmap, all)");
    }
    return m;
}

/// The reference image and the mean of its per-pixel variances (its own squared error): 16x
/// max-spp with another seed, light sampling by MIS with 4 samples; on arealight (direct light
/// only) the correlated estimator with 10 samples (lambda = 1: unbiased, and exact at every
/// point that sees the whole light, so the reference's own variance stays well below the
/// methods' errors; with MIS it exceeded combined's MSE at 64 spp).
Image<Rgb<float>> reference(const std::string& scene_name, const Scene<float>& scene, const DefaultAccel& accel,
                            const Config& cfg, double& ref_var) {
    ref_var = 0;
    if (scene_name == "furnace") return Image<Rgb<float>>(cfg.size, cfg.size, Rgb<float>(1.0f));
    const int spp = 16 * cfg.max_spp;
    std::filesystem::create_directories(cfg.cache);
    const std::string path = cfg.cache + "/" + scene_name + "_" + std::to_string(cfg.size) + "_" +
                             std::to_string(spp) + (cfg.jitter ? "_jitter" : "_centres") + "_v4.exr";
    const std::string var_path = path + ".var";
    if (std::filesystem::exists(path) && std::filesystem::exists(var_path)) {
        std::ifstream(var_path) >> ref_var;
        std::printf("  reference: cached %s\n", path.c_str());
        return read_exr_rgb(path);
    }
    NamedRender<float> o;
    o.image.width = o.image.height = cfg.size;
    o.image.spp = spp;
    o.image.threads = cfg.threads;
    o.tracer.light_samples = 4;
    o.roulette = "spectral";
    o.direct = "mis";
    o.seed = 0x5eed;
    o.image.pixel_jitter = cfg.jitter;
    if (scene_name == "arealight") {
        o.tracer.max_depth = 1;  // direct illumination only
        o.direct = "correlated";
        o.tracer.light_samples = 10;
    }
    const RenderResult r = render_named(scene, any_accel_view(accel), o);
    for (const auto& v : r.variance.pixels) ref_var += double(v[0] + v[1] + v[2]) / (3.0 * double(r.variance.size()));
    std::vector<ExrLayer> layers{ExrLayer{"variance", {"R", "G", "B"}, {}}};
    for (const auto& v : r.variance.pixels) layers[0].data.insert(layers[0].data.end(), {v[0], v[1], v[2]});
    write_exr(path, r.image, layers);
    std::ofstream(var_path) << ref_var;
    std::printf("  reference: %d spp in %.1f s, cached as %s\n", spp, r.seconds, path.c_str());
    return r.image;
}

double rmse(const Image<Rgb<float>>& a, const Image<Rgb<float>>& b, double ref_var) {
    double mse = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            const double d = double(a.pixels[i][c]) - double(b.pixels[i][c]);
            mse += d * d;
        }
    mse /= 3.0 * double(a.size());
    return std::sqrt(std::max(mse - ref_var, mse * 1e-3));
}

void plot(const Config& cfg, const std::map<std::string, std::map<std::string, std::vector<Point>>>& results) {
    if (cfg.plot.empty() || std::system("command -v gnuplot > /dev/null 2>&1") != 0) return;
    // Plot data and script go to a scratch folder, not next to the plot.
    const std::string dir = (std::filesystem::temp_directory_path() / "glint_convergence_plot").string();
    std::filesystem::create_directories(dir);
    std::string script = "set terminal pngcairo size 1200,900 noenhanced\nset output '" + cfg.plot + "'\n"
                         "set logscale xy\nset xlabel 'seconds'\nset ylabel 'RMSE'\nset grid\nset key bottom left\n"
                         "set multiplot layout 2,2\n";
    for (const auto& [scene, methods] : results) {
        script += "set title '" + scene + "'\nplot ";
        bool first = true;
        for (const auto& [method, points] : methods) {
            const std::string dat = dir + "/" + scene + "_" + method + ".dat";
            std::ofstream out(dat);
            for (const Point& p : points) out << p.seconds << ' ' << p.rmse << '\n';
            script += std::string(first ? "" : ", ") + "'" + dat + "' with linespoints title '" + method + "'";
            first = false;
        }
        script += "\n";
    }
    script += "unset multiplot\n";
    const std::string gp = dir + "/plot.gp";
    std::ofstream(gp) << script;
    if (std::system(("gnuplot " + gp).c_str()) == 0) std::printf("wrote %s\n", cfg.plot.c_str());
}

/// Mean over pixels and bands of the per-pixel variance of the mean: the image's MSE at its spp.
double mean_variance(const RenderResult& r) {
    double v = 0;
    for (const auto& p : r.variance.pixels) v += double(p[0] + p[1] + p[2]) / 3.0;
    return v / double(r.variance.size());
}

/// Share of an image's summed per-pixel variance held by its `fraction` noisiest pixels.
double top_pixel_share(const RenderResult& r, double fraction) {
    std::vector<double> v;
    for (const auto& p : r.variance.pixels) v.push_back(double(p[0] + p[1] + p[2]));
    std::sort(v.begin(), v.end(), std::greater<>());
    const std::size_t k = std::max<std::size_t>(1, std::size_t(fraction * double(v.size())));
    const double top = std::accumulate(v.begin(), v.begin() + std::ptrdiff_t(k), 0.0);
    const double all = std::accumulate(v.begin(), v.end(), 0.0);
    return all > 0 ? top / all : 0.0;
}

/// --analysis (furnace): what Szécsi 2009, §2.2's formula can gain in this room at all, from a
/// model with no geometry. The furnace is a cube, and from any face the five others subtend
/// form factors of 0.1998-0.2000, so a cosine-sampled walk moves, on average, to one of the
/// other five walls uniformly. Along that chain each walk's estimate X = sum_k F_k Le_k is
/// exactly 1 per band without roulette (sum_k prod_{j<k} a_j (1 - a_k) telescopes), so all
/// its error is termination's: the model's MSE per band and walk length under the library's
/// own ClassicRoulette and SpectralRoulette predict the tracer's ratio without pixel or
/// geometry noise. (The tracer's camera sees the walls unevenly and per-point form factors
/// vary, so expect agreement within a few percent, not exactly.)
template <class R>
std::pair<double, double> furnace_chain(const Scene<float>& scene, const R& roulette, int first_wall, long walks) {
    std::vector<const Material<float>*> walls;
    for (const auto& m : scene.materials) walls.push_back(&m);
    const int n = int(walls.size());
    if (n < 2) throw Error("furnace_chain: the furnace needs at least two walls");
    Pcg32 rng(11);
    double se = 0, bounces = 0;
    for (long w = 0; w < walks; ++w) {
        int wall = first_wall >= 0 ? first_wall : int(rng.uniform<double>() * n) % n;
        Rgb<float> F(1.0f), X(0.0f);
        for (int depth = 0; depth < 256; ++depth) {
            const Material<float>& m = *walls[std::size_t(wall)];
            X += F * m.emission;
            const float s = roulette.continuation(F, m.kd, depth);
            if (!(rng.uniform<float>() < s)) break;
            F = F * m.kd / s;
            bounces += 1;
            int next = int(rng.uniform<double>() * (n - 1)) % (n - 1);
            wall = next >= wall ? next + 1 : next;
        }
        for (std::size_t c = 0; c < 3; ++c) se += double(X[c] - 1.0f) * double(X[c] - 1.0f);
    }
    return {se / (3.0 * double(walks)), bounces / double(walks)};
}

void furnace_model(const Scene<float>& scene, const Rgb<float>& H, const char* weights) {
    const auto classic = Roulette<float, 3>::classic(H);
    const auto spectral = Roulette<float, 3>::spectral(H);
    const auto [mse_c, len_c] = furnace_chain(scene, classic, -1, 2'000'000);
    const auto [mse_s, len_s] = furnace_chain(scene, spectral, -1, 2'000'000);
    // Rays per walk: the camera ray plus one per bounce; time taken proportional to rays.
    const double eff = (mse_c / mse_s) * ((1.0 + len_c) / (1.0 + len_s));
    std::printf("  chain model (H = %s, 2e6 walks from a random wall, next wall uniform over the others):\n", weights);
    std::printf("    MSE per band: classic %.4f, spectral %.4f (ratio %.3f); bounces per walk %.3f, %.3f\n",
                mse_c, mse_s, mse_c / mse_s, len_c, len_s);
    std::printf("    predicted efficiency spectral / classic (time ~ rays) = %.3f\n", eff);
    // At the first vertex F = 1, so both roulettes continue with the same s = <a, H>; the
    // variance of that first decision, Var(E[X | continue?]) = (1/s - 1) a^2 per band, is
    // common to both methods (walks start on a uniformly chosen wall here).
    double shared = 0;
    for (const auto& m : scene.materials) {
        const float s = classic.continuation(Rgb<float>(1.0f), m.kd, 0);
        for (std::size_t c = 0; c < 3; ++c) shared += (1.0 / s - 1.0) * double(m.kd[c]) * double(m.kd[c]);
    }
    shared /= 3.0 * double(scene.materials.size());
    std::printf("    first decision's variance, common to both: %.4f per band (%.0f%% of classic's MSE); "
                "MSE ratio of the rest %.3f (the most that stratifying the first decisions could give)\n", shared, 100.0 * shared / mse_c, (mse_c - shared) / (mse_s - shared));
    std::printf("    MSE ratio by the wall a walk starts on (the camera's view decides the mix):");
    for (int w = 0; w < int(scene.materials.size()); ++w)
        std::printf(" %.2f", furnace_chain(scene, classic, w, 500'000).first / furnace_chain(scene, spectral, w, 500'000).first);
    std::printf("\n");
}

/// Calls f(tracer) with the path tracer of o's direct lighting and `roulette`.
template <class F>
auto with_tracer(const Scene<float>& scene, const DefaultAccel& accel, const Roulette<float, 3>& roulette,
                 const NamedRender<float>& o, F&& f) {
    PathTracerSettings<float> ts = o.tracer;
    ts.roulette = roulette;
    const DirectChoice<float> direct =
        find_choice(direct_choices<float>(), "direct lighting", o.direct).make(scene, any_accel_view(accel), ts, o.image);
    return std::visit(
        [&]<class D>(const D& d) {
            return f(PathTracer<DefaultAccel, RandomSampler<float>, D>(scene, accel, d, MisEnvironment<float>(scene), ts));
        },
        direct);
}

/// Renders with `roulette` and the direct lighting named by o.direct.
RenderResult render_direct(const Scene<float>& scene, const DefaultAccel& accel, const Roulette<float, 3>& roulette,
                           const NamedRender<float>& o, const RandomSampler<float>& sampler) {
    return with_tracer(scene, accel, roulette, o, [&](const auto& tracer) { return render_image(scene, o.image, tracer, sampler); });
}

/// --analysis (roulette scenes): what bounds the radiance-estimate roulette of Szécsi 2009,
/// §2.3. The goodness d = E[(X - a L~)^2] / E[X^2] of the closed-scene and the pilot-fitted L~,
/// the floor no estimate can go below (the ideal per-vertex L~, from runs of 8 samples at
/// 2048 vertices), and how much of the MSE termination adds at all: classic roulette against
/// none (walks to the depth cap), MSE from the variance images at max-spp, 4 seeds.
void roulette_analysis(const std::string& name, const Scene<float>& scene, const DefaultAccel& accel,
                       const Config& cfg) {
    NamedRender<float> o = methods_for(name, cfg).front().options;  // classic, the scene's lighting
    o.image.spp = cfg.max_spp;
    const Rgb<float> H = cfg.weights == "mean" ? Rgb<float>(1.0f / 3.0f) : Rgb<float>::default_luminance_weights();
    if (name == "furnace") furnace_model(scene, H, cfg.weights.c_str());
    const std::size_t repeats = 8;
    const auto samples = with_tracer(scene, accel, Roulette<float, 3>::classic(H), o, [&](const auto& tracer) {
        return tracer.pilot_samples(o.image, RandomSampler<float>(7), 2048, int(repeats));
    });
    const std::span<const RoulettePilotSample<float, 3>> v(samples);
    Rgb<float> power, albedo;
    float area;
    scene.radiance_estimate_inputs(power, area, albedo);
    const Rgb<float> scene_L = global_radiance_estimate(power, area, albedo), pilot_L = fitted_radiance_estimate(v);
    std::printf("  analysis (direct %s, H = %s): goodness d of L~ (Szécsi 2009, §2.3; 1 = no better than L~ = 0)\n", o.direct.c_str(),
                cfg.weights.c_str());
    std::printf("    scene formula L~ = (%.4f %.4f %.4f)  d = %.3f\n", scene_L[0], scene_L[1], scene_L[2],
                estimate_goodness(v, scene_L, H));
    std::printf("    pilot fit     L~ = (%.4f %.4f %.4f)  d = %.3f\n", pilot_L[0], pilot_L[1], pilot_L[2],
                estimate_goodness(v, pilot_L, H));
    std::printf("    floor (ideal per-vertex L~)             d = %.3f\n", estimate_goodness_floor(v, repeats, H));
    double mse[2] = {0, 0}, seconds[2] = {0, 0}, rays[2] = {0, 0};
    const int seeds = 4;
    double top_share = 0;
    for (int seed = 0; seed < seeds; ++seed)
        for (int k = 0; k < 2; ++k) {
            const RandomSampler<float> sampler(std::uint64_t(1000 + seed));
            const RenderResult r = k == 0 ? render_direct(scene, accel, Roulette<float, 3>::classic(H), o, sampler)
                                          : render_direct(scene, accel, Roulette<float, 3>::none(), o, sampler);
            mse[k] += mean_variance(r) / seeds;
            if (k == 0 && seed == 0) top_share = top_pixel_share(r, 0.01);
            seconds[k] += r.seconds / seeds;
            rays[k] += double(r.rays) / (double(o.image.width) * o.image.height * o.image.spp) / seeds;
        }
    std::printf("    MSE at %d spp: classic %.5g, no roulette %.5g: termination adds %.1f%% of classic's MSE\n",
                cfg.max_spp, mse[0], mse[1], 100.0 * (1.0 - mse[1] / mse[0]));
    std::printf("    rays per camera path: classic %.2f, no roulette %.2f; seconds %.3f, %.3f\n", rays[0], rays[1],
                seconds[0], seconds[1]);
    std::printf("    the 1%% of pixels with the largest variance hold %.1f%% of classic's (camera rays %s)\n",
                100.0 * top_share, cfg.jitter ? "jittered over each pixel" : "through pixel centres");
}

/// --scene envmap: Szécsi 2009, §3.3's comparison, environment lighting at the first vertex only.
/// Per pixel sample, at the point the camera ray through the pixel's centre finds: the
/// environment policy's estimate plus the BRDF sample (the path tracer's continuation ray)
/// weighted by the policy's escaped(), which is MisEnvironment's second strategy and 0 for
/// CorrelatedEnvironment. (The path tracer itself cannot stop there: MIS needs the
/// continuation ray that a depth cap does not trace, and with indirect light the shared
/// path-tracing noise hides the estimators' difference.) Rays that miss the scene see the map.
template <class E>
RenderResult envmap_direct(const Scene<float>& scene, const DefaultAccel& accel, const E& env, int size, int spp,
                           std::uint64_t seed) {
    RenderSettings settings;
    settings.width = settings.height = size;
    settings.pixel_jitter = false;
    const PixelCamera<float> camera(scene.camera, settings);
    RandomSampler<float> sampler(seed);
    RenderResult r;
    r.image = Image<Rgb<float>>(size, size);
    r.variance = Image<Rgb<float>>(size, size);
    const auto start = std::chrono::steady_clock::now();
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            Rgb<double> sum(0.0), square(0.0);
            for (int i = 0; i < spp; ++i) {
                const Ray<float> ray = camera.ray(x, y, std::uint64_t(i), sampler);
                RayQueries<DefaultAccel> queries(accel);
                StoreHit<float> hit;
                Rgb<float> L = env.escaped(ray.direction, Arrival<float>{});
                if (queries.closest_hit(ray, hit)) {
                    ShadingPoint<float> sp = shading_point(scene, hit, scene.normal(hit.id), ray.direction);
                    const Frame<float>& frame = sp.frame;
                    const SurfaceBrdf<float> brdf(scene.materials[scene.material_of[hit.id]], frame.to_local(-ray.direction));
                    sp.brdf = &brdf;
                    L = env.estimate(sp, sampler, queries);
                    const Vec3<float> wi = brdf.sample_by_albedo(sampler.get_2d());
                    const float pdf = brdf.sampling_pdf(wi);
                    const Vec3<float> w = frame.to_world(wi);
                    StoreHit<float> next;
                    if (pdf > 0.0f && wi.z > 0.0f && !queries.closest_hit(spawn(sp, w), next))
                        L += brdf.f(wi) * (wi.z / pdf) * env.escaped(w, Arrival<float>{true, pdf});
                }
                sum += Rgb<double>(L[0], L[1], L[2]);
                square += Rgb<double>(L[0], L[1], L[2]) * Rgb<double>(L[0], L[1], L[2]);
            }
            const Rgb<double> mean = sum / double(spp), var = (square / double(spp) - mean * mean) / double(spp);
            r.image.at(x, y) = Rgb<float>(float(mean[0]), float(mean[1]), float(mean[2]));
            r.variance.at(x, y) = Rgb<float>(float(std::max(0.0, var[0])), float(std::max(0.0, var[1])), float(std::max(0.0, var[2])));
        }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
}

/// The envmap methods: MisEnvironment (importance: the map's importance sampling and the BRDF
/// sample by the balance heuristic, the path tracer's default) and CorrelatedEnvironment with K
/// samples from the same map density: importance-k (lambda = 0), correlated (lambda = 1, main part
/// eq. 3.5 only), combined-3.5 (combined, eq. 3.5 only) and combined (both main parts, chosen per
/// cell and vertex).
RenderResult envmap_method(const std::string& method, const Scene<float>& scene, const DefaultAccel& accel, int size,
                           int spp, std::uint64_t seed, int samples) {
    if (method == "importance") return envmap_direct(scene, accel, MisEnvironment<float>(scene), size, spp, seed);
    CorrelatedEnvironmentSettings cs;
    cs.samples = samples;
    cs.estimator = method == "importance-k" ? DirectEstimator::importance
                   : method == "correlated"  ? DirectEstimator::correlated
                                             : DirectEstimator::combined;
    if (method == "correlated" || method == "combined-3.5") cs.main_part = EnvironmentMainPart::radiance;
    return envmap_direct(scene, accel, CorrelatedEnvironment<float>(scene, cs), size, spp, seed);
}

using Results = std::map<std::string, std::map<std::string, std::vector<Point>>>;
double efficiency_ratio(const std::vector<Point>& m, const std::vector<Point>& base);

/// Whether combined has the lowest RMSE at each level, and its time over `base`'s.
void summarize_combined(const std::map<std::string, std::vector<Point>>& m, const std::vector<std::string>& others,
                        const std::string& base) {
    const auto& com = m.at("combined");
    int lower = 0;
    for (std::size_t i = 0; i < com.size(); ++i) {
        bool lowest = true;
        for (const std::string& o : others) lowest = lowest && com[i].rmse < m.at(o)[i].rmse;
        lower += lowest;
    }
    double t_com = 0, t_base = 0;
    for (std::size_t i = 0; i < com.size(); ++i) t_com += com[i].seconds, t_base += m.at(base)[i].seconds;
    std::printf("  combined has the lowest RMSE at %d of %zu spp levels; time overhead vs %s %+.1f%%\n", lower,
                com.size(), base.c_str(), 100.0 * (t_com / t_base - 1.0));
}

/// --scene envmap: every method at spp = 1, 2, .. max-spp (single thread, levels outer) against
/// a reference of correlated sampling (lambda = 1, unbiased) with 16 samples per vertex at
/// 4x max-spp, another seed; its own variance is subtracted from the MSE.
void envmap_convergence(const Config& cfg, const Scene<float>& scene, const DefaultAccel& accel, std::ofstream& csv,
                        Results& results) {
    const int k = cfg.light_samples > 0 ? cfg.light_samples : CorrelatedEnvironmentSettings{}.samples;
    const RenderResult ref = envmap_method("correlated", scene, accel, cfg.size, 4 * cfg.max_spp, 0x5eed, 16);
    const double ref_var = mean_variance(ref);
    std::printf("  reference: %d spp, 16 samples per vertex, %.1f s; K = %d samples per vertex\n", 4 * cfg.max_spp,
                ref.seconds, k);
    const std::vector<std::string> methods{"importance", "importance-k", "correlated", "combined-3.5", "combined"};
    for (int spp = 1; spp <= cfg.max_spp; spp *= 2)
        for (const std::string& m : methods) {
            const RenderResult r = envmap_method(m, scene, accel, cfg.size, spp, 1000 * cfg.seed + std::uint64_t(spp), k);
            const Point p{spp, r.seconds, rmse(r.image, ref.image, ref_var)};
            results["envmap"][m].push_back(p);
            if (csv) csv << "envmap," << m << ',' << spp << ',' << p.seconds << ',' << p.rmse << '\n';
        }
    std::printf("  %-14s", "spp");
    for (const std::string& m : methods) std::printf(" %14s", m.c_str());
    std::printf("   (RMSE; last row: seconds per sample)\n");
    const auto& by = results["envmap"];
    for (std::size_t i = 0; i < by.at("combined").size(); ++i) {
        std::printf("  %-14d", by.at("combined")[i].spp);
        for (const std::string& m : methods) std::printf(" %14.5f", by.at(m)[i].rmse);
        std::printf("\n");
    }
    const double samples = double(cfg.size) * cfg.size * double(2 * cfg.max_spp - 1);
    std::printf("  %-14s", "us/sample");
    for (const std::string& m : methods) {
        double t = 0;
        for (const Point& p : by.at(m)) t += p.seconds;
        std::printf(" %14.3f", 1e6 * t / samples);
    }
    std::printf("\n  %-14s", "efficiency");
    for (const std::string& m : methods) std::printf(" %13.2fx", efficiency_ratio(by.at(m), by.at("importance")));
    std::printf("   (1 / (MSE seconds) against importance)\n");
    summarize_combined(by, {"importance", "importance-k", "correlated", "combined-3.5"}, "importance");
    summarize_combined(by, {"importance-k"}, "importance-k");
}

/// Geometric mean over spp >= 4 (or all levels when there are fewer) of eff(m) / eff(base).
double efficiency_ratio(const std::vector<Point>& m, const std::vector<Point>& base) {
    double log_sum = 0;
    int n = 0;
    for (std::size_t i = 0; i < m.size() && i < base.size(); ++i) {
        if (m[i].spp < 4 && m.back().spp >= 4) continue;
        const double em = 1.0 / (m[i].rmse * m[i].rmse * m[i].seconds);
        const double eb = 1.0 / (base[i].rmse * base[i].rmse * base[i].seconds);
        log_sum += std::log(em / eb);
        ++n;
    }
    return n ? std::exp(log_sum / n) : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        Config cfg;
        cli::App app("bench_convergence: the path tracer's RMSE against time for the roulettes, BRDF selection, "
                     "correlated sampling and the samplers, single thread per method");
        cli::text(app, "--scene", cfg.scene, "furnace, cornell, cornell-glossy, arealight, envmap or all", "NAME");
        cli::output(app, "--csv", cfg.csv, "write the curves as CSV (and the plot beside it)");
        cli::text(app, "--cache", cfg.cache, "folder of cached references", "DIR");
        cli::output(app, "--plot", cfg.plot, "FILE.png: the plot");
        cli::number(app, "--size", cfg.size, 4, 1 << 14, "image width and height");
        cli::number(app, "--max-spp", cfg.max_spp, 1, 1 << 20, "largest samples per pixel");
        cli::number(app, "--threads", cfg.threads, 0, 1 << 20, "threads (0: all cores)");
        cli::flag(app, "--quick", cfg.quick, "a smoke run: 16 x 16, up to 4 spp");
        cli::text(app, "--direct", cfg.direct, "direct lighting of the roulette and selection scenes (default per scene)",
                  "NAME");
        cli::choice(app, "--estimate", cfg.radiance_estimate, estimate_choices(), "radiance estimate",
                    "L~ of the estimate roulettes");
        cli::flag(app, "--reduce", cfg.reduce, "shorten walks by the estimate's goodness");
        cli::flag(app, "--analysis", cfg.analysis, "Szecsi 2009 2.3's goodness d and termination's share");
        cli::flag(app, "--jitter", cfg.jitter, "camera rays jittered over each pixel (default: through its centre)");
        cli::choice(app, "--sampler", cfg.sampler, sampler_choices<float>(), "sampler", "sampler");
        cli::number(app, "--seed", cfg.seed, std::uint64_t(0), ~std::uint64_t(0), "methods render with seed 1000 N + spp");
        cli::number(app, "--light-samples", cfg.light_samples, 1, 1 << 20,
                    "light samples per vertex (default: 1; 10 on arealight)");
        cli::choice(app, "--weights", cfg.weights, weights_choices<float>(), "roulette weights", "roulette band weights H");
        cli::text(app, "--compare", cfg.compare, "roulette: the roulette methods on every scene", "NAME");
        cli::number(app, "--rr-depth", cfg.rr_depth, 0, 1 << 20, "the throughput roulettes' min_depth");
        if (!cli::parse(app, argc, argv)) return 0;
        if (!cfg.compare.empty() && cfg.compare != "roulette")
            throw Error("--compare expects roulette, not '" + cfg.compare + "'");
        if (cfg.quick) {
            cfg.size = 16;
            cfg.max_spp = 4;
        }
        if (cfg.plot.empty() && !cfg.csv.empty()) {
            const auto dot = cfg.csv.rfind('.');
            cfg.plot = (dot == std::string::npos ? cfg.csv : cfg.csv.substr(0, dot)) + ".png";
        }
        std::vector<std::string> scenes;
        if (cfg.scene == "all") scenes = {"furnace", "cornell", "cornell-glossy", "arealight"};
        else scenes = {cfg.scene};

        Results results;
        std::ofstream csv;
        if (!cfg.csv.empty()) {
            csv.open(cfg.csv);
            if (!csv) throw Error("cannot write " + cfg.csv);
            csv << "scene,method,spp,seconds,rmse\n";
        }
        for (const std::string& name : scenes) {
            const Scene<float> scene = builtin_scene<float>(name);
            const DefaultAccel accel(scene.triangles);
            std::printf("%s (%dx%d, spp 1..%d)\n", name.c_str(), cfg.size, cfg.size, cfg.max_spp);
            double ref_var = 0;
            if (name == "envmap") {
                envmap_convergence(cfg, scene, accel, csv, results);
                continue;
            }
            if (cfg.analysis) {
                if (name == "furnace" || name == "cornell") roulette_analysis(name, scene, accel, cfg);
                continue;
            }
            const Image<Rgb<float>> ref = reference(name, scene, accel, cfg, ref_var);
            const std::vector<Method> methods = methods_for(name, cfg);
            // Levels outer, methods inner: each level's methods run back to back, so that
            // machine load drifts affect them alike.
            for (int spp = 1; spp <= cfg.max_spp; spp *= 2)
                for (const Method& m : methods) {
                    NamedRender<float> o = m.options;
                    o.image.spp = spp;
                    o.seed = 1000 * cfg.seed + std::uint64_t(spp);
                    const RenderResult r = render_named(scene, any_accel_view(accel), o);
                    const Point p{spp, r.seconds, rmse(r.image, ref, ref_var)};
                    results[name][m.name].push_back(p);
                    if (csv) csv << name << ',' << m.name << ',' << spp << ',' << p.seconds << ',' << p.rmse << '\n';
                }
            const std::string& base = methods.front().name;
            const bool field = results[name].count("throughput") > 0;  // the field's baseline was run
            std::printf("  %-28s %10s %10s %12s%s\n", "method", "rmse@max", "seconds", "efficiency",
                        field ? "   efficiency" : "");
            for (const Method& m : methods) {
                const auto& pts = results[name][m.name];
                std::printf("  %-28s %10.5f %10.3f %8.3fx vs %s", m.name.c_str(), pts.back().rmse, pts.back().seconds,
                            efficiency_ratio(pts, results[name][base]), base.c_str());
                if (field) std::printf("  %8.3fx vs throughput", efficiency_ratio(pts, results[name]["throughput"]));
                std::printf("\n");
            }
            if (name == "arealight") summarize_combined(results[name], {"importance", "correlated"}, "importance");
        }
        if (csv.is_open()) std::printf("wrote %s\n", cfg.csv.c_str());
        plot(cfg, results);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_convergence: %s\n", e.what());
        return 1;
    }
}
