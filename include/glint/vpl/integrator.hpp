// glint/vpl/integrator.hpp: the virtual light sources method (Szécsi 2009, §1.4; Keller
// 1997) as an integrator of tracer/renderer.hpp: shooting (vpl/shooting.hpp), then gathering
// (vpl/gather.hpp) at the points the camera sees, under the same Renderer, camera
// (PixelCamera), per-pixel sampler streams and ray queries (RayQueries) as the path tracer.
//
// The Renderer owns the tiles, threads, progress, statistics and film; VplIntegrator owns the
// light transport of one camera ray, with a copy of the visibility policy per rendering thread
// (its thread_state) and the VPL part kept per pixel for the film's "indirect" layer. A pixel
// sample's random numbers (the dielectrics' Fresnel choices, the light samples) come from the
// sampler's stream for (x, y, sample), so images do not depend on the thread count.
// The image's settings (size, samples, jitter, threads) are the caller's RenderSettings, the
// method's the VplSettings. Methods that gather many times at the same pixel points (light
// animation, light path maps) take those points from primary_points, a render of the same
// camera rays with the same streams (PixelPointIntegrator), and gather there with
// gather_image (vpl/gather.hpp).
#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/image.hpp>
#include <glint/core/math.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>
#include <glint/trees/tree.hpp>
#include <glint/vpl/gather.hpp>
#include <glint/vpl/shooting.hpp>

namespace glint {

/// The virtual light sources method as an Integrator over VPLs shot beforehand: for a camera
/// ray, the emission it sees through mirrors and dielectrics, direct illumination at the first
/// diffuse or glossy point and the VPLs' illumination there through the visibility policy
/// (each rendering thread its own copy, thread_state). rays counts the camera path's and the
/// light samples' rays (the visibility policy's tests are its own). The VPL part is kept per
/// pixel and written by finish() to the film layer "indirect".
template <RayAccelerator A, class V, Scalar T = typename A::scalar_type>
    requires VisibilityPolicy<V, T>
class VplIntegrator {
public:
    using scalar_type = T;  ///< Scalar type of the scene and accelerator.
    using thread_state = V;  ///< Each rendering thread's own copy of the visibility policy.
    /// What the integrator accumulates per pixel: the VPL part of its samples.
    struct pixel_state {
        Rgb<T> indirect{T(0)};  ///< sum of the samples' VPL parts (non-finite ones left out)
        std::uint32_t samples = 0;  ///< Number of samples taken of the pixel.
    };

    /// `vpls` must outlive the integrator.
    VplIntegrator(const Scene<T>& s, const A& accel, std::span<const Vpl<T>> vpls, const V& visibility,
                  const VplSettings& st)
        : scene_(s), accel_(accel), lights_(s), vpls_(vpls, st), visibility_(visibility), st_(st),
          d2min_(T(st.min_distance * st.min_distance)) {
        st.validate();
        s.require_untextured("glint::VplIntegrator");
    }

    /// A copy of the visibility policy for one rendering thread.
    V make_thread_state() const { return visibility_; }

    /// Radiance along camera ray `ray`: emission seen, direct light (when st.direct) and the
    /// VPLs' part (when st.indirect; also added to `state`), drawing uniforms from `sampler`.
    template <class S>
        requires Sampler<S, T>
    PathSample<T> radiance(const Ray<T>& ray, S& sampler, pixel_state& state, V& vis) const {
        RayQueries<A> rays(accel_);
        const auto uniform = [&sampler] { return sampler.get_1d(); };
        const PixelPoint<T> p = surface_seen(scene_, rays, ray, st_.max_specular, uniform);
        PathSample<T> out;
        if (st_.direct) {
            out.L = p.emitted;
            if (p.hit) out.L += direct_light(scene_, rays, lights_, p, st_.light_samples, uniform);
        }
        if (st_.indirect && p.hit) {
            const Rgb<T> indirect = vpls_.gather(scene_, p, vis, d2min_) * p.weight;
            if (indirect.is_finite()) state.indirect += indirect;
            out.L += indirect;
        }
        ++state.samples;
        out.rays = rays.rays();
        return out;
    }

    /// Appends the layer "indirect" to `film`: each pixel's mean VPL part (0 without samples).
    void finish(Film& film, std::span<const pixel_state> states) const {
        FilmLayer layer{"indirect", Image<Rgb<float>>(film.image.width, film.image.height)};
        for (std::size_t i = 0; i < states.size() && i < layer.pixels.pixels.size(); ++i)
            for (std::size_t c = 0; c < 3; ++c)
                layer.pixels.pixels[i][c] = states[i].samples ? float(states[i].indirect[c] / T(states[i].samples)) : 0.0f;
        film.layers.push_back(std::move(layer));
    }

private:
    const Scene<T>& scene_;
    const A& accel_;
    EmitterSet<T> lights_;
    VplLights<T> vpls_;  // every VPL, or their cluster tree for st.gather = cuts
    V visibility_;
    VplSettings st_;
    T d2min_;
};

/// What render_vpl returns: the renderer's result (image, variance, rays, seconds: shooting
/// included), the image's VPL part, and the shooting's count and time.
struct VplResult : RenderResult {
    Image<Rgb<float>> indirect;  ///< The VPL part of the image (per-pixel mean), also inside `image`.
    std::size_t vpls = 0;  ///< Number of VPLs gathered from.
    double shooting_seconds = 0;  ///< Wall-clock seconds of the shooting phase (0 for render_vpls).
};

/// Gathering from VPLs shot beforehand (none for direct illumination alone), through the
/// Renderer with `image`'s settings and visibility policy V; the sampler's streams are those
/// of st.seed.
template <RayAccelerator A, class V, Scalar T = typename A::scalar_type>
    requires VisibilityPolicy<V, T>
VplResult render_vpls(const Scene<T>& s, const A& accel, std::span<const Vpl<T>> vpls, const V& visibility,
                      const RenderSettings& image, const VplSettings& st) {
    const VplIntegrator<A, V, T> integrator(s, accel, vpls, visibility, st);
    VplResult out;
    static_cast<RenderResult&>(out) = render_image(s, image, integrator, RandomSampler<T>(st.seed));
    out.vpls = vpls.size();
    for (FilmLayer& layer : out.layers)
        if (layer.name == "indirect") out.indirect = std::move(layer.pixels);
    std::erase_if(out.layers, [](const FilmLayer& l) { return l.name == "indirect"; });
    return out;
}

/// The whole method: shooting st.vpl_walks walks with roulette R (when st.indirect), then
/// gathering through the Renderer.
template <RayAccelerator A, class R, class V, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T> && VisibilityPolicy<V, T>
VplResult render_vpl(const Scene<T>& s, const A& accel, const R& roulette, const V& visibility,
                     const RenderSettings& image, const VplSettings& st) {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    st.validate();
    s.validate();
    const std::vector<Vpl<T>> vpls =
        st.indirect ? shoot_scene_vpls(s, accel, roulette, st.vpl_walks, st.seed, st.shooting) : std::vector<Vpl<T>>{};
    const double shooting = std::chrono::duration<double>(clock::now() - t0).count();
    VplResult out = render_vpls(s, accel, std::span<const Vpl<T>>(vpls), visibility, image, st);
    out.shooting_seconds = shooting;
    out.seconds = std::chrono::duration<double>(clock::now() - t0).count();
    return out;
}

/// A film of pixel points: what PixelPointIntegrator leaves per pixel, row by row.
template <Scalar T>
struct PointFilm {
    std::vector<PixelPoint<T>> points;  ///< One point per pixel, row-major (y * width + x).
    /// Makes room for width x height default (missed) points.
    void resize(int width, int height) { points.assign(std::size_t(width) * std::size_t(height), PixelPoint<T>{}); }
    /// Ignores the Renderer's colours: a point film keeps only points (written by finish()).
    void set_pixel(int, int, const Rgb<T>&, const Rgb<T>&) {}
};

/// An integrator that only finds, per pixel, the first diffuse or glossy point its camera ray
/// sees (surface_seen, with the same stream as VplIntegrator's): one sample per pixel.
template <RayAccelerator A, Scalar T = typename A::scalar_type>
class PixelPointIntegrator {
public:
    using scalar_type = T;  ///< Scalar type of the scene and accelerator.
    using pixel_state = PixelPoint<T>;  ///< The point a pixel's camera ray found.

    /// Points of `s` found through `accel`, following at most max_specular mirror or dielectric
    /// vertices; both must outlive the integrator.
    PixelPointIntegrator(const Scene<T>& s, const A& accel, int max_specular)
        : scene_(s), accel_(accel), max_specular_(max_specular) {
        s.require_untextured("glint::PixelPointIntegrator");
    }

    /// Stores the point `ray` sees in `state` and returns the emission seen on the way.
    template <class S>
        requires Sampler<S, T>
    PathSample<T> radiance(const Ray<T>& ray, S& sampler, pixel_state& state) const {
        RayQueries<A> rays(accel_);
        state = surface_seen(scene_, rays, ray, max_specular_, [&sampler] { return sampler.get_1d(); });
        return {state.emitted, rays.rays(), false};
    }

    /// Copies the pixels' points into `film`.
    void finish(PointFilm<T>& film, std::span<const pixel_state> states) const {
        film.points.assign(states.begin(), states.end());
    }

private:
    const Scene<T>& scene_;
    const A& accel_;
    int max_specular_;
};

/// The camera's pixel points, row by row: one camera ray per pixel (image.spp is taken as 1),
/// the same rays and streams as render_vpls with the same image settings and st.seed, so the
/// fixed-point gathers and the Renderer's images see the same points.
template <RayAccelerator A, Scalar T = typename A::scalar_type>
std::vector<PixelPoint<T>> primary_points(const Scene<T>& s, const A& accel, RenderSettings image, const VplSettings& st) {
    st.validate();
    s.validate();
    image.spp = 1;
    PointFilm<T> film;
    render_image(s, image, PixelPointIntegrator<A, T>(s, accel, st.max_specular), RandomSampler<T>(st.seed), film);
    return std::move(film.points);
}

}  // namespace glint
