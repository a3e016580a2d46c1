// moving_object: a box floating through the Cornell box, its photons maintained by selective
// photon tracing and its indirect light by texel caches (Larsen 2004, ch. 9-11).
//
//   moving_object [--frames F] [--size S] [--photons N] [--groups G] [--texels T]
//                 [--aim-groups A] [--texel-size X] [--threads K] [--hold H] [--out DIR]
//
// Every frame the box moves; one pilot photon per group is re-traced and the groups whose
// pilot changed are emitted again (glint/photons/selective_tracing.hpp); the texel caches
// then refresh at most A surface groups' approximated illumination and T texels' gathered
// indirect irradiance (glint/photons/texel_cache.hpp). The image is direct light by shadow
// rays to the area light (a fixed 4 x 4 grid of points on each light triangle, the same every
// frame) plus kd / pi times the texel caches' indirect irradiance. After the F frames of
// motion the box rests for H more frames (default 0). For comparison the frame
// is also recomputed from scratch: every photon traced, every texel updated. Prints per frame
// the time of the maintained frame's update and of the recomputed one's photons and texels
// (K threads; the rendering, the same for both, is left out), the photons
// re-emitted and the RMSE of the maintained image against the recomputed one; writes
// DIR/frame_NNN.png (maintained) and DIR/reference_NNN.png (recomputed) for the last frame.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#define GLINT_STB_IMPLEMENTATION  // stb_image_write's functions, compiled in this file
#include <glint/io/png.hpp>
#include <glint/photons/selective_tracing.hpp>
#include <glint/photons/surface_groups.hpp>
#include <glint/photons/texel_cache.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;
using Accel = MeshBvh<MollerTrumbore<float>, 8>;

namespace {

/// The Cornell box with a 0.3-wide box floating at x = `x`, above the short box.
Scene<float> scene_at(float x) {
    Scene<float> s = builtin_scene<float>("cornell");
    const auto grey = s.add_material(Material<float>::lambertian(Rgb<float>(0.6f, 0.6f, 0.65f)));
    detail::add_box(s, Vec3<float>(x - 0.15f, 1.0f, 0.30f), Vec3<float>(x + 0.15f, 1.3f, 0.60f), 0.5f, grey);
    return s;
}

bool occluded(const Accel& accel, const Vec3<float>& x, const Vec3<float>& n, const Vec3<float>& y) {
    Ray<float> r = detail::light_spawn(x, n, glm::normalize(y - x));
    r.tmax = glm::length(y - x) * 0.999f;
    StoreHit<float> hit;
    return accel.closest_hit(r, hit);
}

/// Direct light at x (normal n, facing the viewer) from the emissive triangles, 16 fixed points each.
Rgb<float> direct(const Scene<float>& s, const Accel& accel, const Vec3<float>& x, const Vec3<float>& n) {
    Rgb<float> sum(0.0f);
    for (std::uint32_t t = 0; t < s.triangles.size(); ++t) {
        const Material<float>& m = s.materials[s.material_of[t]];
        if (!m.emissive()) continue;
        const auto& v = s.triangles[t];
        const Vec3<float> nl = s.normal(t);
        const float area = triangle_area(v[0], v[1], v[2]);
        for (int k = 0; k < 16; ++k) {
            const Vec3<float> y = sample_triangle(v[0], v[1], v[2], Vec2<float>((float(k % 4) + 0.5f) / 4, (float(k / 4) + 0.5f) / 4));
            const Vec3<float> d = y - x;
            const float r2 = glm::dot(d, d), c = glm::dot(n, d), cl = -glm::dot(nl, d);
            if (c <= 0.0f || cl <= 0.0f || occluded(accel, x, n, y)) continue;
            sum += m.emission * (c * cl / (r2 * r2) * area / 16.0f);
        }
    }
    return sum;
}

Image<Rgb<float>> render(const Scene<float>& s, const Accel& accel, const TexelCache<float>& cache, int size) {
    Image<Rgb<float>> img(size, size);
    for (int py = 0; py < size; ++py)
        for (int px = 0; px < size; ++px) {
            const Ray<float> ray = s.camera.ray((float(px) + 0.5f) / float(size), (float(py) + 0.5f) / float(size), 1.0f);
            StoreHit<float> hit;
            if (!accel.closest_hit(ray, hit)) continue;
            const Material<float>& m = s.materials[s.material_of[hit.id]];
            const Vec3<float> x = ray.at(hit.t), ng = s.normal(hit.id);
            const Vec3<float> n = glm::dot(ng, ray.direction) < 0.0f ? ng : -ng;
            const Rgb<float> e = glm::dot(ng, ray.direction) < 0.0f ? m.emission : Rgb<float>(0.0f);
            img.at(px, py) = e + m.kd * (direct(s, accel, x, n) + cache.indirect(s, hit.id, x)) / pi<float>;
        }
    return img;
}

double rmse(const Image<Rgb<float>>& a, const Image<Rgb<float>>& b) {
    double sum = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) sum += std::pow(double(a.pixels[i][c]) - double(b.pixels[i][c]), 2);
    return std::sqrt(sum / double(3 * a.pixels.size()));
}

double mean(const Image<Rgb<float>>& a) {
    double sum = 0;
    for (const auto& p : a.pixels) sum += double(p[0] + p[1] + p[2]);
    return sum / double(3 * a.pixels.size());
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) try {
    int frames = 24, size = 64, threads = 2, hold = 0;
    SelectiveTracingSettings st;
    st.photons.photons = 50000;
    st.photons.emission = PhotonEmission::halton;
    st.groups = 2310;
    TexelCacheSettings ts;
    ts.texel_size = 0.25f;
    ts.estimate = {50, 0.5f};
    std::string dir = ".";
    cli::App app("moving_object: selective photon tracing and texel caches while a box moves through the Cornell box");
    cli::number(app, "--frames", frames, 1, 1 << 16, "frames");
    cli::number(app, "--size", size, 1, 4096, "image width and height");
    cli::number(app, "--photons", st.photons.photons, std::size_t(1), std::size_t(1) << 32, "photons per full trace");
    cli::number(app, "--groups", st.groups, std::size_t(1), std::size_t(1) << 24, "photon groups");
    cli::number(app, "--texels", ts.texels_per_frame, std::size_t(0), std::size_t(1) << 32, "IIM updates (texels) per frame");
    cli::number(app, "--aim-groups", ts.groups_per_frame, std::size_t(0), std::size_t(1) << 24, "AIM updates (whole groups) per frame");
    cli::number(app, "--texel-size", ts.texel_size, 1e-6f, 1e6f, "texel edge length");
    cli::number(app, "--threads", threads, 1, 4096, "worker threads");
    cli::number(app, "--hold", hold, 0, 1 << 16, "frames the box holds still first");
    cli::folder(app, "--out", dir, "folder for the images");
    if (!cli::parse(app, argc, argv)) return 0;
    st.photons.threads = ts.threads = threads;
    const auto x_at = [&](int f) { return -0.6f + 1.2f * float(std::min(f, frames - 1)) / float(std::max(frames - 1, 1)); };

    Scene<float> scene = scene_at(x_at(0));
    const SurfaceGroups groups = surface_groups<float>(scene.triangles, 0.5f);
    SelectivePhotons<float> photons(scene, Accel(scene.triangles), st);
    TexelCache<float> cache(scene, groups, ts);
    cache.update_all(scene, Accel(scene.triangles), photons.photons());
    std::printf("%d frames of %dx%d, %zu photons in %zu groups, %zu texels (%zu per frame), %d threads\n", frames, size,
                size, st.photons.photons, st.groups, cache.texels(), ts.texels_per_frame, threads);
    std::printf("frame   box_x  maintained_s  recomputed_s  reemitted  aim_groups  iim_texels       rmse  mean_ref\n");
    for (int f = 1; f < frames + hold; ++f) {
        scene = scene_at(x_at(f));
        auto t0 = std::chrono::steady_clock::now();
        const Accel accel(scene.triangles);
        const SelectiveFrame sf = photons.update(scene, accel);
        cache.record(sf);
        const TexelUpdate tu = cache.update(scene, accel, photons.photons());
        const double maintained = seconds_since(t0);
        const Image<Rgb<float>> img = render(scene, accel, cache, size);

        t0 = std::chrono::steady_clock::now();
        const Accel accel_ref(scene.triangles);
        TexelCache<float> fresh(scene, groups, ts);
        fresh.update_all(scene, accel_ref, trace_photons(scene, accel_ref, st.photons));
        const double recomputed = seconds_since(t0);
        const Image<Rgb<float>> ref = render(scene, accel_ref, fresh, size);
        std::printf("%5d  %6.3f  %12.4f  %12.4f  %9zu  %10zu  %10zu  %9.5f  %8.4f\n", f, x_at(f), maintained, recomputed,
                    sf.reemitted, tu.aim_groups, tu.iim_texels, rmse(img, ref), mean(ref));
        char name[64];
        std::snprintf(name, sizeof name, "%s/frame_%03d.png", dir.c_str(), f);
        write_png(name, img);
        if (f == frames + hold - 1) {
            std::snprintf(name, sizeof name, "%s/reference_%03d.png", dir.c_str(), f);
            write_png(name, ref);
        }
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
}
