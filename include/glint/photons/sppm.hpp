// glint/photons/sppm.hpp: stochastic progressive photon mapping (Hachisuka and Jensen 2009),
// the field's consistent photon-mapping baseline (pbrt-v4's SPPMIntegrator is the same
// method). Each pass:
//   1. the camera pass, under the Renderer: one jittered camera ray per pixel, followed
//      through mirrors and dielectrics to its first diffuse or glossy vertex, the pixel's
//      visible point (photons/visible_points.hpp); the passes continue one randomized Halton
//      sequence per pixel (pass k draws the pixel's samples k c .. k c + c - 1 for c camera
//      samples), as pbrt-v4's SPPMIntegrator continues its sampler, so that emission seen
//      directly and direct light converge like the path tracer's progressive passes;
//   2. a hash grid over the visible points and their current radii (photons/hash_grid.hpp);
//   3. the photon pass: photons traced from the lights (photons/photon_tracing.hpp) without
//      the first hits of direct light (PhotonSettings::store_direct off), every stored photon
//      (global and caustic) looked up in the grid and its power, weighted by the throughput
//      and the BRDF of each visible point whose sphere holds it, added to that point's pass
//      flux;
//   4. each pixel's statistics updated (photons/sppm_statistics.hpp, alpha = 2/3 by default).
// Direct light at the visible points comes from a lighting policy of tracer/lighting.hpp (the
// caller's; glint-render uses MisDirect: light samples and a BRDF sample by the balance
// heuristic), as pbrt-v4's SPPMIntegrator does, and photons bring the rest (caustics and
// indirect light); emission the camera path meets counts whole. The image after K passes is
// (emission + direct) / K + tau / (pi R^2 K). A pass may take several camera rays per pixel
// for emission and direct light (SppmSettings::camera_samples), the visible point of one of
// them (sample k mod c in pass k) gathering the photons: the light's edges and direct light's
// noise then get more samples than the photon pass's points, at the cost of a few rays (each
// part stays an unbiased pixel average).
//
// Deterministic for a seed whatever the thread count: the camera pass draws from per-pixel
// sequences, photon tracing is deterministic, and the photon pass splits the photons into
// fixed chunks whose contributions are summed per pixel in chunk order.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/parallel.hpp>
#include <glint/photons/hash_grid.hpp>
#include <glint/photons/photon_tracing.hpp>
#include <glint/photons/sppm_statistics.hpp>
#include <glint/photons/surface_area.hpp>
#include <glint/photons/visible_points.hpp>
#include <glint/sampling/halton.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/progressive.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// Stochastic progressive photon mapping's knobs: photons per pass, initial radius, alpha, depths.
struct SppmSettings {
    std::size_t photons = 100000;  ///< Photons emitted per pass; > 0.
    double radius = 0.05;          ///< Initial gather radius (scene units); > 0.
    double alpha = 2.0 / 3.0;      ///< The fraction of a pass's photons kept (radius reduction), in (0, 1].
    int max_specular = 32;         ///< Camera paths: specular vertices before the visible point; >= 0.
    int camera_samples = 1;        ///< Camera rays per pixel and pass for emission and direct light; >= 1.
    int photon_depth = 32;         ///< Photon paths: bounces (PhotonSettings::max_depth); >= 1.
    /// A photon counts at a visible point when the cosine between its surface normal and the
    /// point's is at least this, and the estimate divides by the area of the point's surface
    /// group (triangles joined across edges whose normals meet it) inside R, not by pi R^2
    /// (photons/surface_area.hpp); -1: every photon in the sphere from the point's front side
    /// over the whole disc (Hachisuka and Jensen 2009's estimate). In [-1, 1].
    double surface_cos = 0.9;
    std::uint64_t seed = 0;        ///< The render's seed; each pass derives its camera and photon seeds from it.

    /// Throws Error for a setting outside the ranges above.
    void validate() const {
        if (photons == 0) throw Error("SPPM needs at least one photon per pass");
        if (!(radius > 0.0) || !std::isfinite(radius)) throw Error("SPPM radius must be positive, got " + std::to_string(radius));
        check_sppm_alpha(alpha);
        if (max_specular < 0 || photon_depth < 1) throw Error("SPPM depths must be >= 0 (camera) and >= 1 (photons)");
        if (camera_samples < 1) throw Error("SPPM camera samples must be >= 1, got " + std::to_string(camera_samples));
        if (!(surface_cos >= -1.0 && surface_cos <= 1.0))
            throw Error("SPPM surface cosine must be in [-1, 1], got " + std::to_string(surface_cos));
    }
};

/// What render_sppm returns: the image (RenderResult: rays are the camera passes'), the
/// passes done, the photons emitted in all and the mean final radius over the pixels.
struct SppmResult : ProgressiveResult {
    std::size_t photons_emitted = 0;  ///< Photons emitted over all passes.
    double mean_radius = 0;           ///< Mean final gather radius over the pixels (scene units).
    double photon_seconds = 0;  ///< Seconds of photon tracing and lookups.
};

namespace detail {

/// Per-pass seeds: the camera pass's sampler and the photon tracing's, from the render's.
inline std::uint64_t pass_seed(std::uint64_t seed, int pass, std::uint64_t salt) {
    return mix_bits(seed ^ mix_bits(std::uint64_t(pass) * 0x9E3779B97F4A7C15ull + salt));
}

/// One photon's BRDF-weighted contribution to one pixel's pass flux.
struct FluxSplat {
    std::uint32_t pixel;
    Rgb<float> flux;
};

/// The photon pass: every photon of `photons` looked up in `grid` (over the visible points
/// `points`, whose pixels are `pixel_of`), in fixed chunks; the chunks' splats are summed
/// into m and phi per pixel in chunk order, so the sums do not depend on the thread count.
template <Scalar T>
void splat_photons(const Scene<T>& s, std::span<const Photon> photons, const SphereHashGrid<T>& grid,
                   std::span<const VisiblePoint<T>> points, std::span<const std::uint32_t> pixel_of, T surface_cos,
                   int threads, std::vector<double>& m, std::vector<Rgb<double>>& phi) {
    constexpr std::size_t chunk = 1 << 13;
    const int chunks = int((photons.size() + chunk - 1) / chunk);
    std::vector<std::vector<FluxSplat>> out(std::size_t(std::max(chunks, 0)));
    parallel_blocks(chunks, threads, [&](std::atomic<int>& next) {
        for (int c = next++; c < chunks; c = next++) {
            const std::size_t end = std::min(photons.size(), std::size_t(c + 1) * chunk);
            for (std::size_t j = std::size_t(c) * chunk; j < end; ++j) {
                const Photon& ph = photons[j];
                const Vec3<T> x(ph.position), wi = -Vec3<T>(ph.direction()), normal(ph.normal());
                const Rgb<float> power = ph.power();
                grid.query(x, [&](std::size_t i, T) {
                    if (surface_cos > T(-1) && glm::dot(normal, points[i].n) < surface_cos) return;
                    const Rgb<T> w = points[i].weight(s, wi);
                    if (w.max() > T(0))
                        out[std::size_t(c)].push_back({pixel_of[i], Rgb<float>(float(w[0]) * power[0], float(w[1]) * power[1],
                                                                               float(w[2]) * power[2])});
                });
            }
        }
    });
    for (const auto& splats : out)
        for (const FluxSplat& f : splats) {
            m[f.pixel] += 1.0;
            phi[f.pixel] += Rgb<double>(double(f.flux[0]), double(f.flux[1]), double(f.flux[2]));
        }
}

/// SPPM's photon pass `pass` over the visible points of `film`: the hash grid over them with
/// their current radii, the photons traced without direct hits and splatted, each point's
/// flux divided by the share of its disc its surface covers (`areas`; null: the whole disc),
/// and each pixel's statistics updated. Returns the photons emitted.
template <RayAccelerator A, Scalar T>
std::size_t sppm_photon_pass(const Scene<T>& s, const A& accel, const VisiblePointFilm<T>& film, const SppmSettings& st,
                             const SurfaceAreas<T>* areas, int pass, int threads, std::vector<SppmStatistics>& stats) {
    std::vector<Vec3<T>> centres;
    std::vector<T> radii;
    std::vector<VisiblePoint<T>> points;
    std::vector<std::uint32_t> pixel_of;
    for (std::size_t p = 0; p < stats.size(); ++p) {
        if (!film.points[p].valid) continue;
        centres.push_back(film.points[p].x);
        radii.push_back(T(std::sqrt(stats[p].r2)));
        points.push_back(film.points[p]);
        pixel_of.push_back(std::uint32_t(p));
    }
    const SphereHashGrid<T> grid{std::span<const Vec3<T>>(centres), std::span<const T>(radii)};
    PhotonSettings ps;
    ps.photons = st.photons;
    ps.seed = pass_seed(st.seed, pass, 2);
    ps.max_depth = st.photon_depth;
    ps.threads = threads;
    ps.store_direct = false;  // direct light is the lighting policy's
    const PhotonSet set = trace_photons(s, accel, ps);
    std::vector<double> m(stats.size(), 0.0);
    std::vector<Rgb<double>> phi(stats.size(), Rgb<double>(0.0));
    for (const auto* map : {&set.global, &set.caustic})
        splat_photons(s, std::span<const Photon>(*map), grid, std::span<const VisiblePoint<T>>(points),
                      std::span<const std::uint32_t>(pixel_of), T(areas ? st.surface_cos : -1.0), threads, m, phi);
    // The flux over the surface's part of the disc, scaled to the whole disc: tau then keeps its
    // meaning (flux within pi R^2) whichever point a pass keeps.
    if (areas)
        for (std::size_t i = 0; i < points.size(); ++i) {
            const double share = areas->disc_share(points[i].triangle, points[i].x, double(radii[i]));
            if (share > 0) phi[pixel_of[i]] /= share;
        }
    for (std::size_t p = 0; p < stats.size(); ++p) stats[p].update(m[p], phi[p], st.alpha);
    return set.emitted;
}

}  // namespace detail

/// Stochastic progressive photon mapping of `s` through accelerator `accel` with the image
/// settings `image` (spp is ignored: st.camera_samples camera rays per pixel and pass), passes until
/// `budget` says stop.
template <RayAccelerator A, class D, Scalar T = typename A::scalar_type>
    requires DirectLighting<D, T, RayQueries<A>, HaltonSampler<T>>
SppmResult render_sppm(const Scene<T>& s, const A& accel, const D& direct, const RenderSettings& image,
                       const SppmSettings& st, const PassBudget& budget) {
    st.validate();
    budget.validate();
    s.validate();
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
    std::vector<SppmStatistics> stats(pixels, SppmStatistics{st.radius * st.radius, 0.0, Rgb<double>(0.0)});
    std::vector<Rgb<double>> lit(pixels, Rgb<double>(0.0));  // emission met and direct light
    SppmResult out;
    RenderSettings camera = image;
    camera.progress = nullptr;
    camera.spp = st.camera_samples;
    // The pixel, the Fresnel choices and direct light's first samples from Halton, PCG after.
    const std::optional<SurfaceAreas<T>> areas =
        st.surface_cos > -1.0 ? std::optional<SurfaceAreas<T>>(std::in_place, std::span<const TriangleVertices<T>>(s.triangles),
                                                                T(std::acos(st.surface_cos)))
                              : std::nullopt;
    const HaltonSampler<T> sampler(image.width, image.height, render_halton_dims, HaltonRandomization::digit_permutation,
                                   detail::pass_seed(st.seed, 0, 1));
    for (int pass = 0;; ++pass) {
        VisiblePointFilm<T> film;
        camera.first_sample = image.first_sample + std::uint64_t(pass) * std::uint64_t(st.camera_samples);
        // Pass k keeps sample k mod c's visible point: over the passes the kept points' leading
        // Halton digits cycle (see VisiblePointIntegrator).
        const RenderStats rs =
            visible_points(s, accel, direct, camera, st.max_specular, sampler, film, pass % st.camera_samples);
        out.rays += rs.rays;
        out.paths += rs.paths;
        const auto photon_start = clock::now();
        for (std::size_t p = 0; p < pixels; ++p)
            lit[p] += Rgb<double>(double(film.radiance[p][0]), double(film.radiance[p][1]), double(film.radiance[p][2]));
        out.photons_emitted += detail::sppm_photon_pass(s, accel, film, st, areas ? &*areas : nullptr, pass, image.threads, stats);
        out.photon_seconds += std::chrono::duration<double>(clock::now() - photon_start).count();
        out.passes = pass + 1;
        if (budget.stop(out.passes, std::chrono::duration<double>(clock::now() - start).count())) break;
    }
    out.image = Image<Rgb<float>>(image.width, image.height);
    out.variance = Image<Rgb<float>>(image.width, image.height);
    double radius_sum = 0;
    for (std::size_t p = 0; p < pixels; ++p) {
        const Rgb<double> L = lit[p] / double(out.passes) + stats[p].radiance(out.passes);
        for (std::size_t c = 0; c < 3; ++c) out.image.pixels[p][c] = float(L[c]);
        radius_sum += std::sqrt(stats[p].r2);
    }
    out.mean_radius = radius_sum / double(std::max<std::size_t>(pixels, 1));
    out.seconds = std::chrono::duration<double>(clock::now() - start).count();
    return out;
}

}  // namespace glint
