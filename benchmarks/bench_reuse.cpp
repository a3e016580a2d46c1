// bench_reuse: light animation with path reuse (Szécsi 2009, ch. 7) against rendering the frames
// independently, on the Cornell box lit by a point light moving under the ceiling.
//
//   bench_reuse [--quick] [--csv FILE] [--size S] [--frames 10,100] [--ref-walks R] [--reps K] [--threads T]
//               [--clamp D]
//
// Every image (reference included) clamps the VPL geometry term at distance D (default 0.1,
// the box is 2 wide; 0: unclamped): unclamped VPL estimates near corners have infinite
// variance (the integral of G^2 over the VPLs' area diverges like the integral of r^-4 dA),
// so that their RMSE measures the luck of a few spikes; clamped, all methods estimate the
// same (biased) quantity with finite variance.
// For each frame count F: a reference of the indirect illumination (R walks per frame, on
// every frame for F <= 10, else on every (F/10)th frame), then, each at its measured time
// (shooting, connections, gathering, combination; the camera's visible points are shared):
//   independent  k paths per frame, independent random numbers (k = 1, 2, 4, ..., F);
//   dependent    k paths per frame, the same random numbers in every frame;
//   reuse        1 own + (F - 1) borrowed paths per frame (Szécsi 2009, §7.2);
//   reuse-split  the same with each path split into 10 at its first hit (section 7.2.1);
//   online       1 own path per frame + those of the last W - 1 frames (section 7.3, W = 10).
// Every method runs --reps times with different seeds (times and flicker averaged, rmse the
// root of the mean squared error). rmse: relative RMSE of the indirect illumination against the reference over the reference
// frames; flicker: mean absolute difference between consecutive frames (per pixel and band,
// over all frames; the reference row gives the true change). The reference's own noise is
// printed (half-against-half RMSE / 2). A summary prints the equal-time RMSE ratio and the
// equal-RMSE speedup of reuse over independent sampling (log-log interpolation along the
// independent rows; past the last row, extrapolation with RMSE ~ time^-1/2, said so).
//   CSV columns: scene,method,frames,paths,seconds,rmse,flicker
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/vpl/integrator.hpp>
#include <glint/vpl/light_animation.hpp>
#include <glint/vpl/scenes.hpp>

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

using Accel = MeshBvh<MollerTrumbore<float>, 8>;
/// The classic (albedo) roulette of the shooting walks.
glint::Roulette<float, 3> classic() { return glint::Roulette<float, 3>::classic(); }
using Img = std::vector<Rgb<float>>;

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct Setup {
    explicit Setup(Scene<float> sc) : scene(std::move(sc)), accel(scene.triangles) {}
    Scene<float> scene;
    Accel accel;
    RenderSettings image;  // the camera's pixels (points gathered at, threads)
    double clamp = 0.1;    // the geometry-term clamp of every image
    std::vector<PixelPoint<float>> points;
    std::vector<Vec3<float>> track;
    Rgb<float> intensity{4.0f, 3.5f, 3.0f};
};

/// Indirect illumination of frame f with `walks` independent walks (seed).
Img independent_frame(const Setup& s, std::size_t f, std::size_t walks, std::uint64_t seed) {
    Scene<float> sf = s.scene;
    sf.point_lights[0].position = s.track[f];
    const std::vector<Vpl<float>> vpls = shoot_scene_vpls(sf, s.accel, classic(), walks, seed);
    return gather_image(sf, std::span<const PixelPoint<float>>(s.points), std::span<const Vpl<float>>(vpls),
                        ShadowRayVisibility<Accel>(s.accel, 1e-4f), s.clamp, s.image.threads);
}

double sq(double x) { return x * x; }

/// Relative RMSE of frames against the reference frames (ref[k] is frame ref_frames[k]).
double rmse(const std::vector<Img>& frames, const std::vector<Img>& ref, const std::vector<std::size_t>& ref_frames) {
    double num = 0, den = 0;
    for (std::size_t k = 0; k < ref.size(); ++k)
        for (std::size_t i = 0; i < ref[k].size(); ++i)
            for (std::size_t c = 0; c < 3; ++c) {
                num += sq(double(frames[ref_frames[k]][i][c]) - ref[k][i][c]);
                den += sq(ref[k][i][c]);
            }
    return std::sqrt(num / den);
}

double flicker(const std::vector<Img>& frames) {
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t f = 1; f < frames.size(); ++f)
        for (std::size_t i = 0; i < frames[f].size(); ++i)
            for (std::size_t c = 0; c < 3; ++c, ++n) sum += std::abs(double(frames[f][i][c]) - frames[f - 1][i][c]);
    return n ? sum / double(n) : 0.0;
}

struct Row {
    std::string method;
    std::size_t frames, paths;
    double seconds, rmse, flicker;
};

/// Path reuse: shoot, connect, one image per path, combine every frame (window 0: all).
std::vector<Img> reuse_frames(const Setup& s, std::size_t paths, int branches, std::size_t window, std::uint64_t seed) {
    AnimationOptions opt;
    opt.paths_per_frame = paths;
    opt.branches = branches;
    opt.seed = seed;
    LightAnimation<float> a = shoot_light_animation(s.scene, s.accel, classic(), std::span<const Vec3<float>>(s.track),
                                                    s.intensity, opt);
    render_path_images(a, s.scene, std::span<const PixelPoint<float>>(s.points), ShadowRayVisibility<Accel>(s.accel, 1e-4f),
                       s.clamp, s.image.threads);
    std::vector<Img> out;
    for (std::size_t f = 0; f < a.frames(); ++f) out.push_back(a.frame_image(f, window));
    return out;
}

/// Log-log interpolation of y at x along points sorted by x; past the ends, the slope `tail`.
double interpolate(const std::vector<std::pair<double, double>>& pts, double x, double tail, bool& extrapolated) {
    extrapolated = x < pts.front().first || x > pts.back().first;
    if (x <= pts.front().first) return pts.front().second * std::pow(x / pts.front().first, tail);
    if (x >= pts.back().first) return pts.back().second * std::pow(x / pts.back().first, tail);
    for (std::size_t i = 1; i < pts.size(); ++i)
        if (x <= pts[i].first) {
            const double t = std::log(x / pts[i - 1].first) / std::log(pts[i].first / pts[i - 1].first);
            return pts[i - 1].second * std::pow(pts[i].second / pts[i - 1].second, t);
        }
    return pts.back().second;
}

void summary(const std::vector<Row>& rows, std::size_t F) {
    std::vector<std::pair<double, double>> t_to_e, e_to_t;
    for (const Row& r : rows)
        if (r.method == "independent" && r.frames == F) t_to_e.push_back({r.seconds, r.rmse});
    std::sort(t_to_e.begin(), t_to_e.end());
    for (const auto& p : t_to_e) e_to_t.push_back({p.second, p.first});
    std::sort(e_to_t.begin(), e_to_t.end());
    for (const Row& r : rows) {
        if (r.frames != F || r.method == "independent" || r.method == "dependent" || r.method == "reference") continue;
        bool ex1, ex2;
        const double e_ind = interpolate(t_to_e, r.seconds, -0.5, ex1);
        const double t_ind = interpolate(e_to_t, r.rmse, -2.0, ex2);
        std::printf("F=%zu %-12s rmse %.4f in %.2f s; independent at equal time: rmse %.4f (ratio %.2f%s); "
                    "independent at equal rmse: %.2f s (speedup %.1fx%s)\n",
                    F, r.method.c_str(), r.rmse, r.seconds, e_ind, e_ind / r.rmse, ex1 ? ", extrapolated" : "", t_ind,
                    t_ind / r.seconds, ex2 ? ", extrapolated" : "");
    }
}

}  // namespace

int main(int argc, char** argv) {
    std::string csv;
    int size = 48, threads = 0;
    std::size_t ref_walks = 8192;
    std::uint64_t reps = 8;
    std::vector<std::size_t> frame_counts{10, 100};
    bool quick = false;
    double clamp = 0.1;
    cli::App app("bench_reuse: path reuse across the frames of a moving point light (Szecsi 2009, 7.3) against "
                 "independent paths");
    cli::output(app, "--csv", csv, "write the rows as CSV");
    cli::number(app, "--size", size, 1, 1 << 14, "image width and height");
    cli::number(app, "--threads", threads, 0, 4096, "threads (0: all cores)");
    cli::number(app, "--ref-walks", ref_walks, std::size_t(2), std::size_t(1) << 30, "reference walks per frame");
    cli::number(app, "--reps", reps, std::uint64_t(1), std::uint64_t(1) << 20, "repetitions");
    cli::number(app, "--clamp", clamp, 0.0, 1e30, "clamp the geometry term at this distance");
    cli::flag(app, "--quick", quick, "a smoke run: 16 x 16, 64 reference walks, 4 frames, 2 repetitions");
    cli::numbers(app, "--frames", frame_counts, std::size_t(1), std::size_t(1) << 20, "frame counts F");
    cli::parse_or_exit(app, argc, argv, "bench_reuse");
    if (quick) size = 16, ref_walks = 64, frame_counts = {4}, reps = 2;
    Setup s(with_point_light(builtin_scene<float>("cornell"), Vec3<float>(0, 1.7f, 0.2f), Rgb<float>(4.0f, 3.5f, 3.0f)));
    s.image.width = s.image.height = size;
    s.image.threads = threads;
    s.image.spp = 1;
    s.image.pixel_jitter = false;
    s.clamp = clamp;
    s.points = primary_points(s.scene, s.accel, s.image, VplSettings{});
    std::vector<Row> rows;
    for (const std::size_t F : frame_counts) {
        s.track = light_track(Vec3<float>(-0.7f, 1.7f, 0.2f), Vec3<float>(0.7f, 1.7f, 0.2f), F);
        std::vector<std::size_t> ref_frames;
        for (std::size_t f = 0; f < F; f += std::max<std::size_t>(1, F / 10)) ref_frames.push_back(f);
        std::vector<Img> ref, all_ref;
        double ref_noise = 0, ref_den = 0;
        for (const std::size_t f : ref_frames) {
            const Img a = independent_frame(s, f, ref_walks / 2, 900001 + f), b = independent_frame(s, f, ref_walks / 2, 700001 + f);
            Img m(a.size());
            for (std::size_t i = 0; i < a.size(); ++i) {
                m[i] = (a[i] + b[i]) * 0.5f;
                for (std::size_t c = 0; c < 3; ++c) ref_noise += sq(double(a[i][c]) - b[i][c]), ref_den += sq(m[i][c]);
            }
            ref.push_back(m);
        }
        std::printf("F=%zu: reference %zu walks on %zu frames, its own relative noise %.4f\n", F, ref_walks,
                    ref_frames.size(), std::sqrt(ref_noise / ref_den) / 2);
        if (ref_frames.size() == F) rows.push_back({"reference", F, ref_walks, 0.0, 0.0, flicker(ref)});
        auto run = [&](const std::string& method, std::size_t paths, auto&& make) {
            double seconds = 0, mse = 0, flick = 0;
            for (std::uint64_t rep = 0; rep < reps; ++rep) {
                const double t0 = now();
                const std::vector<Img> frames = make(1000 * rep);
                seconds += (now() - t0) / double(reps);
                mse += sq(rmse(frames, ref, ref_frames)) / double(reps);
                flick += flicker(frames) / double(reps);
            }
            rows.push_back({method, F, paths, seconds, std::sqrt(mse), flick});
            const Row& r = rows.back();
            std::printf("%-12s F=%-4zu paths=%-4zu %8.3f s  rmse %.4f  flicker %.5f\n", r.method.c_str(), F, paths,
                        r.seconds, r.rmse, r.flicker);
            std::fflush(stdout);
        };
        for (std::size_t k = 1; k <= F; k *= 2)
            for (const bool dependent : {false, true})
                run(dependent ? "dependent" : "independent", k, [&](std::uint64_t seed) {
                    std::vector<Img> out;
                    for (std::size_t f = 0; f < F; ++f)
                        out.push_back(independent_frame(s, f, k, seed + (dependent ? 5 : 5 + 7919 * f)));
                    return out;
                });
        run("reuse", 1, [&](std::uint64_t seed) { return reuse_frames(s, 1, 1, 0, 11 + seed); });
        run("reuse-split", 1, [&](std::uint64_t seed) { return reuse_frames(s, 1, 10, 0, 11 + seed); });
        if (F > 10) run("online", 1, [&](std::uint64_t seed) { return reuse_frames(s, 1, 1, 10, 11 + seed); });
        summary(rows, F);
    }
    if (!csv.empty()) {
        std::ofstream out(csv);
        if (!out) throw Error("bench_reuse: cannot write '" + csv + "'");
        out << "scene,method,frames,paths,seconds,rmse,flicker\n";
        for (const Row& r : rows)
            out << s.scene.name << ',' << r.method << ',' << r.frames << ',' << r.paths << ',' << r.seconds << ',' << r.rmse
                << ',' << r.flicker << '\n';
    }
    return 0;
}
