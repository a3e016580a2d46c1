// light_path_maps: precomputed light path maps (Szécsi 2009, ch. 8) on the Cornell box lit by a
// point light that moves under the ceiling: preprocessing once, then every frame costs one
// shadow ray per entry point and a weighted sum of panes.
//
//   light_path_maps [--entries E] [--clusters C] [--grid G] [--inset S] [--branches B] [--frames F]
//                   [--size S] [--clamp D] [--ref-walks R] [--seed N] [--out DIR]
//
// Prints the preprocessing time, the map's memory, the mean time per frame, and for each
// frame the relative RMSE of the indirect illumination against a VPL reference of R walks
// (the same clamp D), next to a VPL render that took the LPM's per-frame time (its walk
// count calibrated from a timed 64-walk render) and the fewest VPL walks (powers of 2) that
// reach the LPM's error. Both are the indirect illumination at the same pixel points. Writes DIR/lpm_NNN.png (direct + indirect)
// and DIR/strip_lpm.png (the indirect illumination of the frames side by side).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#define GLINT_STB_IMPLEMENTATION  // stb_image_write's functions, compiled in this file
#include <glint/io/png.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/vpl/integrator.hpp>
#include <glint/vpl/light_path_maps.hpp>
#include <glint/vpl/scenes.hpp>
#include "image_error.hpp"

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

using Accel = MeshBvh<MollerTrumbore<float>, 8>;

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

int main(int argc, char** argv) try {
    LightPathMapOptions opt;
    opt.entry_points = 1024;
    opt.grid = 8;
    opt.min_distance = 0.1;
    std::size_t frames = 8, ref_walks = 4096;
    int size = 96;
    std::string dir = ".";
    cli::App app("light_path_maps: light path maps against VPL renders of the Cornell box with a moving point light");
    cli::number(app, "--entries", opt.entry_points, std::size_t(1), std::size_t(1) << 24, "entry points");
    cli::number(app, "--clusters", opt.clusters, std::size_t(0), std::size_t(1) << 24, "k-means clusters of entry points (0: no clustering)");
    cli::number(app, "--grid", opt.grid, 1, 256, "reference grid per triangle (g x g sub-triangles)");
    cli::number(app, "--inset", opt.inset, 0.0, 0.999, "the grid lattice shrunk toward each centroid (0: on the edges)");
    cli::number(app, "--branches", opt.branches, 1, 1 << 16, "walks per entry point (the splitting factor)");
    cli::number(app, "--frames", frames, std::size_t(1), std::size_t(1) << 16, "frames");
    cli::number(app, "--size", size, 1, 4096, "image width and height");
    cli::number(app, "--clamp", opt.min_distance, 0.0, 1e30, "clamp the geometry term at this distance");
    cli::number(app, "--ref-walks", ref_walks, std::size_t(1), std::size_t(1) << 24, "reference VPL walks");
    cli::number(app, "--seed", opt.seed, std::uint64_t(0), ~std::uint64_t(0), "random seed");
    cli::folder(app, "--out", dir, "folder for the images");
    if (!cli::parse(app, argc, argv)) return 0;
    Scene<float> scene = with_point_light(builtin_scene<float>("cornell"), Vec3<float>(0, 1.7f, 0.2f), Rgb<float>(4.0f, 3.5f, 3.0f));
    const Accel accel(scene.triangles);
    const ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    const auto roulette = Roulette<float, 3>::classic();
    const auto track = light_track(Vec3<float>(-0.7f, 1.7f, 0.2f), Vec3<float>(0.7f, 1.7f, 0.2f), frames);
    // One camera ray through each pixel's centre; the LPM and the VPL renders it is compared
    // with gather at the pixel points the Renderer sees with the same settings and seed.
    const RenderSettings image{.width = size, .height = size, .spp = 1, .pixel_jitter = false};
    const VplSettings direct_only{.indirect = false};
    const auto points = primary_points(scene, accel, image, direct_only);
    const std::span<const PixelPoint<float>> pts(points);

    double t0 = now();
    const LightPathMap<float> map = build_light_path_map(scene, accel, roulette, vis, opt);
    const double pre = now() - t0;
    std::printf("LPM: %zu entry points, %zu panes, %zu reference points; preprocessing %.2f s, %.1f MiB\n",
                map.entries.size(), map.panes.size(), map.grid.size(), pre, double(map.bytes()) / (1 << 20));

    // The VPL method's indirect illumination at the same pixel points: shooting + gathering.
    auto vpl_indirect = [&](std::size_t walks, std::uint64_t seed) {
        const auto vpls = shoot_scene_vpls(scene, accel, roulette, walks, seed);
        return gather_image(scene, pts, std::span<const Vpl<float>>(vpls), vis, opt.min_distance, image.threads);
    };
    scene.point_lights[0].position = track[0];
    t0 = now();
    (void)vpl_indirect(64, 1);
    const double per_walk = (now() - t0) / 64.0;  // calibrates the equal-time VPL renders

    double lpm_seconds = 0;
    std::vector<std::vector<Rgb<float>>> indirect_frames;
    for (std::size_t f = 0; f < frames; ++f) {
        scene.point_lights[0].position = track[f];
        t0 = now();
        const auto e = entry_irradiance(map, scene, accel, 1, f);
        const auto ref_e = reference_irradiance(map, std::span<const Rgb<float>>(e));
        const auto indirect = light_path_map_image(map, scene, pts, std::span<const Rgb<float>>(ref_e));
        const double dt = now() - t0;
        lpm_seconds += dt / double(frames);
        const auto r = vpl_indirect(ref_walks, 77 + f);
        const std::size_t walks = std::max<std::size_t>(1, std::size_t(dt / per_walk));
        t0 = now();
        const auto v = vpl_indirect(walks, 5 + f);
        const double vt = now() - t0;
        const double e_lpm = relative_rmse(std::span<const Rgb<float>>(indirect), std::span<const Rgb<float>>(r));
        // Equal error: the fewest walks (powers of 2, up to R / 2) whose render is as close.
        std::size_t eq = 1;
        double eq_t = 0, eq_e = 0;
        for (; eq <= ref_walks / 2; eq *= 2) {
            const double t1 = now();
            eq_e = relative_rmse(std::span<const Rgb<float>>(vpl_indirect(eq, 300 + f)), std::span<const Rgb<float>>(r));
            eq_t = now() - t1;
            if (eq_e <= e_lpm) break;
        }
        std::printf("frame %zu: LPM %.4f s, rel. RMSE %.3f | VPL at equal time: %zu walks %.4f s, rel. RMSE %.3f | "
                    "VPL at equal RMSE: %zu walks %.4f s, rel. RMSE %.3f\n",
                    f, dt, e_lpm, walks, vt, relative_rmse(std::span<const Rgb<float>>(v), std::span<const Rgb<float>>(r)), eq, eq_t, eq_e);
        // Direct illumination through the Renderer (no VPLs), then the LPM's indirect part.
        Image<Rgb<float>> img = render_vpls(scene, accel, std::span<const Vpl<float>>(), vis, image, direct_only).image;
        for (std::size_t i = 0; i < img.size(); ++i) img.pixels[i] += indirect[i];
        char name[64];
        std::snprintf(name, sizeof name, "%s/lpm_%03zu.png", dir.c_str(), f);
        write_png(name, img);
        indirect_frames.push_back(indirect);
    }
    Image<Rgb<float>> strip(size * int(frames), size);
    for (std::size_t f = 0; f < frames; ++f)
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) strip.at(int(f) * size + x, y) = indirect_frames[f][std::size_t(y * size + x)];
    write_png(dir + "/strip_lpm.png", strip, 1.0f);
    std::printf("mean LPM time per frame %.4f s (%.0f frames/s)\n", lpm_seconds, 1.0 / lpm_seconds);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
}
