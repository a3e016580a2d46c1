// light_animation: a point light moving under the ceiling of the Cornell box, rendered with
// the virtual light sources method and light-path reuse (Szécsi 2009, ch. 7).
//
//   light_animation [--frames F] [--size S] [--paths N] [--window W] [--out DIR]
//
// Every frame shoots N paths from its own light position (N = 1 by default); every path is
// reused in every frame by connecting its first hit to that frame's light, weighted by the
// balance heuristic over the frames (glint/vpl/light_animation.hpp). --window W > 0 reuses
// only the last W frames (the on-line variant of Szécsi 2009, §7.3). Writes, into DIR
// (default "."):
//   frame_NNN.exr / .png             direct + indirect illumination with path reuse;
//   strip_reuse.png                  the indirect illumination of 5 frames side by side;
//   strip_independent.png            the same frames with their own N paths only.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/io/exr.hpp>
#define GLINT_STB_IMPLEMENTATION  // stb_image_write's functions, compiled in this file
#include <glint/io/png.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/vpl/integrator.hpp>
#include <glint/vpl/light_animation.hpp>
#include <glint/vpl/scenes.hpp>

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

/// `frames` images of w x h side by side.
Image<Rgb<float>> strip(const std::vector<std::vector<Rgb<float>>>& frames, int w, int h) {
    Image<Rgb<float>> out(w * int(frames.size()), h);
    for (std::size_t k = 0; k < frames.size(); ++k)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) out.at(int(k) * w + x, y) = frames[k][std::size_t(y * w + x)];
    return out;
}

}  // namespace

int main(int argc, char** argv) try {
    std::size_t frames = 10, paths = 1, window = 0;
    int size = 128;
    std::string dir = ".";
    cli::App app("light_animation: VPL frames of the Cornell box with a moving point light, path reuse across frames");
    cli::number(app, "--frames", frames, std::size_t(1), std::size_t(1) << 16, "frames");
    cli::number(app, "--size", size, 1, 4096, "image width and height");
    cli::number(app, "--paths", paths, std::size_t(1), std::size_t(1) << 24, "light paths per frame");
    cli::number(app, "--window", window, std::size_t(0), std::size_t(1) << 16, "reuse only the last W frames (0: every frame)");
    cli::folder(app, "--out", dir, "folder for the images");
    if (!cli::parse(app, argc, argv)) return 0;
    const Rgb<float> intensity(4.0f, 3.5f, 3.0f);
    Scene<float> scene = with_point_light(builtin_scene<float>("cornell"), Vec3<float>(0, 1.7f, 0.2f), intensity);
    const MeshBvh<MollerTrumbore<float>, 8> accel(scene.triangles);
    const auto track = light_track(Vec3<float>(-0.7f, 1.7f, 0.2f), Vec3<float>(0.7f, 1.7f, 0.2f), frames);
    // One camera ray through each pixel's centre; the pixel points where every path's VPLs
    // are gathered are those the Renderer sees with the same settings and seed.
    const RenderSettings image{.width = size, .height = size, .spp = 1, .pixel_jitter = false};
    const VplSettings direct_only{.indirect = false};
    const auto points = primary_points(scene, accel, image, direct_only);
    const ShadowRayVisibility<MeshBvh<MollerTrumbore<float>, 8>> vis(accel, 1e-4f);

    // Shooting, connections and one image per path; then each frame is a weighted sum.
    AnimationOptions opt;
    opt.paths_per_frame = paths;
    LightAnimation<float> anim = shoot_light_animation(scene, accel, Roulette<float, 3>::classic(),
                                                       std::span<const Vec3<float>>(track), intensity, opt);
    render_path_images(anim, scene, std::span<const PixelPoint<float>>(points), vis, 0.0, image.threads);

    std::vector<std::vector<Rgb<float>>> reuse_strip, own_strip;
    for (std::size_t f = 0; f < frames; ++f) {
        const std::vector<Rgb<float>> indirect = anim.frame_image(f, window);
        scene.point_lights[0].position = track[f];
        // Direct illumination through the Renderer (no VPLs), then the frame's indirect part.
        Image<Rgb<float>> full = render_vpls(scene, accel, std::span<const Vpl<float>>(), vis, image, direct_only).image;
        for (std::size_t i = 0; i < full.size(); ++i) full.pixels[i] += indirect[i];
        char name[64];
        std::snprintf(name, sizeof name, "%s/frame_%03zu", dir.c_str(), f);
        write_exr(std::string(name) + ".exr", full);
        write_png(std::string(name) + ".png", full);
        if (frames < 5 || f % (frames / 5) == 0) {
            reuse_strip.push_back(indirect);
            std::vector<Rgb<float>> own(indirect.size(), Rgb<float>(0.0f));  // this frame's own paths only
            for (std::size_t p = f * paths; p < (f + 1) * paths; ++p)
                for (std::size_t i = 0; i < own.size(); ++i) own[i] += anim.images[p][i];
            own_strip.push_back(own);
        }
    }
    // The indirect illumination is dim next to the direct: one stop brighter in the strips.
    write_png(dir + "/strip_reuse.png", strip(reuse_strip, size, size), 1.0f);
    write_png(dir + "/strip_independent.png", strip(own_strip, size, size), 1.0f);
    std::printf("%zu frames of %dx%d, %zu path(s) per frame%s, written to %s\n", frames, size, size, paths,
                window ? (", on-line window " + std::to_string(window)).c_str() : "", dir.c_str());
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
}
