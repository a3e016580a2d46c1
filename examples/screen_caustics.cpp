// screen_caustics: the screen-space caustic filter (Larsen 2004, ch. 12) on the cornell-caustics
// scene against a long photon-map render of the same caustic irradiance.
//
//   screen_caustics [--size S] [--photons N] [--ref-photons M] [--ref-k K] [--out DIR]
//
// Caustic photons (L S+ D) from N emitted photons are splatted into an S x S image and
// filtered (glint/photons/caustic_filter.hpp); the reference is the caustic map's irradiance
// estimate (k = K nearest, cone filter k_c = 1, photons/radiance_estimate.hpp) from M emitted
// photons at each pixel's visible point, and, for comparison, the same estimate (k = 50) from
// the N photons the filter used. Prints, over the caustic (the pixels whose reference exceeds
// a tenth of its 99th percentile) and over every diffuse pixel: the ratio of summed
// irradiance to the reference's (the relative bias of the caustic's power) and the RMSE over
// the reference's mean. Writes DIR/caustic_filter.png and DIR/caustic_reference.png.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#define GLINT_STB_IMPLEMENTATION  // stb_image_write's functions, compiled in this file
#include <glint/io/png.hpp>
#include <glint/photons/caustic_filter.hpp>
#include <glint/photons/photon_map.hpp>
#include <glint/photons/photon_tracing.hpp>
#include <glint/photons/radiance_estimate.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;
using Accel = MeshBvh<MollerTrumbore<float>, 8>;

namespace {

/// The caustic map's irradiance estimate at every diffuse pixel's visible point.
Image<Rgb<float>> photon_map_image(const std::vector<ScreenSurface>& screen, int size, std::vector<Photon> caustic,
                                   std::size_t k) {
    const PhotonMap map(std::move(caustic));
    RadianceEstimateSettings est{k, 0.2f, PhotonFilter::cone, 1.0f};
    std::vector<PhotonNeighbour> scratch;
    Image<Rgb<float>> out(size, size);
    for (std::size_t i = 0; i < screen.size(); ++i)
        if (screen[i].diffuse) out.pixels[i] = irradiance_estimate(map, screen[i].position, screen[i].normal, est, scratch);
    return out;
}

/// Summed irradiance over the reference's and RMSE over the reference's mean, on a mask.
void compare(const char* what, const char* region, const Image<Rgb<float>>& a, const Image<Rgb<float>>& ref,
             const std::vector<char>& mask) {
    double sa = 0, sr = 0, se = 0, n = 0;
    for (std::size_t i = 0; i < mask.size(); ++i)
        if (mask[i]) {
            const double x = a.pixels[i].luminance(), r = ref.pixels[i].luminance();
            sa += x, sr += r, se += (x - r) * (x - r), n += 1;
        }
    std::printf("%-22s %-10s %8.0f %12.4f %12.4f\n", what, region, n, sa / sr, std::sqrt(se / n) / (sr / n));
}

}  // namespace

int main(int argc, char** argv) try {
    int size = 128;
    std::size_t photons = 200000, ref_photons = 4000000, ref_k = 200;
    std::string dir = ".";
    cli::App app("screen_caustics: the screen-space caustic filter against a photon-map reference");
    cli::number(app, "--size", size, 1, 4096, "image width and height");
    cli::number(app, "--photons", photons, std::size_t(1), std::size_t(1) << 32, "caustic photons");
    cli::number(app, "--ref-photons", ref_photons, std::size_t(1), std::size_t(1) << 32, "reference photons");
    cli::number(app, "--ref-k", ref_k, std::size_t(1), std::size_t(1) << 16, "reference photons per estimate");
    cli::folder(app, "--out", dir, "folder for the images");
    if (!cli::parse(app, argc, argv)) return 0;
    const Scene<float> s = builtin_scene<float>("cornell-caustics");
    const Accel accel(s.triangles);
    const std::vector<ScreenSurface> screen = screen_surfaces(s, accel, size, size);
    PhotonSettings ps;
    ps.photons = photons;
    ps.emission = PhotonEmission::halton;
    PhotonSet set = trace_photons(s, accel, ps);
    const Image<Rgb<float>> filtered = caustic_filter(ScreenProjection(s.camera, size, size), size, size, screen, set.caustic);
    const Image<Rgb<float>> same_n = photon_map_image(screen, size, set.caustic, 50);
    ps.photons = ref_photons;
    ps.seed = 2;
    const Image<Rgb<float>> ref = photon_map_image(screen, size, trace_photons(s, accel, ps).caustic, ref_k);

    std::vector<float> lum;
    for (const auto& p : ref.pixels) lum.push_back(p.luminance());
    std::vector<float> sorted = lum;
    std::sort(sorted.begin(), sorted.end());
    const float cut = 0.1f * sorted[std::size_t(0.99 * double(sorted.size() - 1))];
    std::vector<char> caustic(lum.size()), diffuse(lum.size());
    for (std::size_t i = 0; i < lum.size(); ++i) caustic[i] = lum[i] > cut, diffuse[i] = screen[i].diffuse;
    std::printf("%dx%d, %zu photons (%zu caustic) against %zu (k = %zu)\n", size, size, photons, set.caustic.size(), ref_photons, ref_k);
    std::printf("%-22s %-10s %8s %12s %12s\n", "estimate", "pixels", "count", "sum/ref", "rmse/mean");
    compare("screen filter 7x7", "caustic", filtered, ref, caustic);
    compare("screen filter 7x7", "diffuse", filtered, ref, diffuse);
    compare("photon map k=50", "caustic", same_n, ref, caustic);
    compare("photon map k=50", "diffuse", same_n, ref, diffuse);
    write_png(dir + "/caustic_filter.png", filtered, -2.0f);
    write_png(dir + "/caustic_reference.png", ref, -2.0f);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
}
