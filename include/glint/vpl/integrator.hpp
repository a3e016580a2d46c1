// glint/vpl/integrator.hpp: the virtual light sources method as an integrator over the
// ordinary Scene: shooting (vpl/shooting.hpp), then gathering at the points the camera sees.
//
// 000 section 1.4, gathering: a shading point x seen through a pixel (after
// any mirror or dielectric vertices, followed deterministically with a Fresnel choice) gets
//   L(x) = Le(x) + L_direct(x) + sum_vpl f_r(x, wi) dPhi (kd_y / pi) cos(theta_x) cos(theta_y) / |x - y|^2 V(x, y)
// where f_r(x) is the hit material's full BRDF (SurfaceBrdf) and the VPL reflects diffusely.
// L_direct samples the real lights (emitter by power, uniform on an area light; shadow rays
// through the accelerator). V(x, y) is a VisibilityPolicy (occluders/visibility.hpp):
// ShadowRayVisibility (exact shadow rays, tracer/vpl.hpp) or the occluder-sphere searches
// of 000 chapter 5 (approximate). The VPL geometry term diverges as |x - y| -> 0; the usual
// clamp replaces |x - y|^2 by max(|x - y|^2, d_min^2) (VplSettings::min_distance; 0 = off;
// Kollig and Keller 2004 analyse the bias it leaves).
// Clamping only removes energy, so its bias is negative (tests/test_vpl.cpp measures it;
// docs/vpl.md reports it).
// VplIntegrator is the method as an Integrator of tracer/renderer.hpp: the Renderer owns the
// tiles, threads, progress, statistics and film, as for the path tracer; the integrator owns
// the light transport of one camera ray, with a copy of the visibility policy per rendering
// thread (its thread_state) and the VPL part kept per pixel for the film's "indirect" layer.
// render_vpl shoots, then renders through the Renderer with one camera ray per pixel through
// the pixel's centre; a pixel's random numbers come from the sampler's stream for that pixel,
// so images do not depend on the thread count.
// For methods that gather the same pixel points many times (light_animation.hpp,
// light_path_maps.hpp), primary_points, direct_image and gather_image work on a fixed array
// of points, rows in parallel.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/image.hpp>
#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/vpl/shooting.hpp>

namespace glint {

struct VplSettings {
    int width = 256, height = 256;
    int threads = 0;             // 0: std::thread::hardware_concurrency()
    std::size_t vpl_walks = 256; // shooting walks (each leaves a VPL per non-specular hit)
    double min_distance = 0;     // geometry-term clamp (0: unclamped, unbiased)
    int light_samples = 1;       // real-light samples per pixel for direct illumination
    bool direct = true;          // emission seen directly plus direct illumination
    bool indirect = true;        // the VPLs' illumination
    std::uint64_t seed = 1;
    ShootingOptions shooting{};
    int max_specular = 16;       // mirror/dielectric vertices followed from the camera

    void validate() const {
        if (width <= 0 || height <= 0)
            throw Error("glint::VplSettings: size " + std::to_string(width) + "x" + std::to_string(height) + " must be positive");
        if (!(min_distance >= 0) || !std::isfinite(min_distance))
            throw Error("glint::VplSettings: min_distance " + std::to_string(min_distance) + " must be finite and >= 0");
        if (light_samples < 1) throw Error("glint::VplSettings: light_samples " + std::to_string(light_samples) + " < 1");
    }
};

/// The first non-specular point seen through a pixel, with the camera path's weight.
template <Scalar T>
struct PixelPoint {
    Vec3<T> x{0}, n{0}, wo{0};  // position, normal facing the viewer, direction to the viewer
    Rgb<T> weight{};            // product of the specular reflectances before x
    Rgb<T> emitted{};           // emission seen along the camera path (weighted)
    std::uint32_t material = 0;
    std::uint32_t triangle = 0;  // the scene triangle at x, and x's barycentrics (u, v) on it
    T u = 0, v = 0;
    bool hit = false;
};

/// A source of independent uniforms in [0, 1): a callable returning T (a sampler's get_1d, a
/// Pcg32 stream).
template <class U, class T>
concept UniformSource = std::invocable<U&> && std::convertible_to<std::invoke_result_t<U&>, T>;

namespace detail {

/// An accelerator that counts the rays traced through it (one per closest_hit or any_hit):
/// made for one camera ray's rays and read once they are traced.
template <SceneAccelerator A>
class CountedRays {
public:
    using scalar_type = typename A::scalar_type;
    explicit CountedRays(const A& accel) : accel_(accel) {}
    bool closest_hit(const Ray<scalar_type>& ray, StoreHit<scalar_type>& hit) const {
        ++rays_;
        return accel_.closest_hit(ray, hit);
    }
    bool any_hit(const Ray<scalar_type>& ray) const {
        ++rays_;
        return accel_.any_hit(ray);
    }
    std::uint64_t rays() const { return rays_; }

private:
    const A& accel_;
    mutable std::uint64_t rays_ = 0;
};

/// Runs worker(next_row) on `threads` threads (0: hardware concurrency); workers take rows
/// from the shared counter until none is left.
template <class Worker>
void run_rows(int rows, int threads, const Worker& worker) {
    std::atomic<int> next{0};
    int n = threads > 0 ? threads : int(std::thread::hardware_concurrency());
    n = std::clamp(n, 1, std::max(rows, 1));
    std::vector<std::thread> pool;
    for (int i = 1; i < n; ++i) pool.emplace_back([&] { worker(next); });
    worker(next);
    for (auto& t : pool) t.join();
}

/// Pixel (x, y)'s own random stream for `seed`.
inline Pcg32 pixel_rng(int x, int y, std::uint64_t seed) {
    return Pcg32::hashed(seed ^ 0x51ed, (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x));
}

}  // namespace detail

/// Follows a camera ray through mirrors and dielectrics (at most max_specular of them; the
/// dielectrics' Fresnel choices drawn from `uniform`) to the first diffuse or glossy point.
template <SceneAccelerator A, class U, Scalar T = typename A::scalar_type>
    requires UniformSource<U, T>
PixelPoint<T> surface_seen(const Scene<T>& s, const A& accel, Ray<T> ray, int max_specular, U&& uniform) {
    PixelPoint<T> p;
    p.weight = Rgb<T>(T(1));
    p.emitted = Rgb<T>(T(0));
    for (int k = 0; k <= max_specular; ++k) {
        StoreHit<T> hit;
        if (!accel.closest_hit(ray, hit)) return p;
        const Material<T>& m = s.materials[s.material_of[hit.id]];
        const Vec3<T> ng = s.normal(hit.id), d = safe_normalize(ray.direction);
        const bool front = glm::dot(ng, d) < T(0);
        const Vec3<T> x = ray.at(hit.t), n = front ? ng : -ng;
        if (front && m.emissive()) p.emitted += p.weight * m.emission;
        if (!m.specular()) {
            p.x = x, p.n = n, p.wo = -d, p.material = s.material_of[hit.id], p.hit = true;
            p.triangle = hit.id, p.u = hit.u, p.v = hit.v;
            return p;
        }
        p.weight *= specular_albedo(m);
        ray = detail::vpl_spawn(x, n, specular_direction(m, d, ng, T(uniform())));
    }
    return p;
}

/// The first diffuse or glossy point seen through the centre of pixel (px, py).
template <SceneAccelerator A, Scalar T = typename A::scalar_type>
PixelPoint<T> primary_point(const Scene<T>& s, const A& accel, int px, int py, const VplSettings& st, Pcg32& rng) {
    const T aspect = T(st.width) / T(st.height);
    const Ray<T> ray = s.camera.ray((T(px) + T(0.5)) / T(st.width), (T(py) + T(0.5)) / T(st.height), aspect);
    return surface_seen(s, accel, ray, st.max_specular, [&rng] { return rng.uniform<T>(); });
}

/// Direct illumination at p from `samples` real-light samples (shadow rays through accel),
/// three uniforms each.
template <SceneAccelerator A, class U, Scalar T = typename A::scalar_type>
    requires UniformSource<U, T>
Rgb<T> direct_light(const Scene<T>& s, const A& accel, const EmitterSet<T>& lights, const PixelPoint<T>& p,
                    int samples, U&& uniform) {
    const Frame<T> frame = Frame<T>::from_normal(p.n);
    const SurfaceBrdf<T> brdf(s.materials[p.material], frame.to_local(p.wo));
    Rgb<T> sum(T(0));
    for (int i = 0; i < samples; ++i) {
        T pdf;
        const T u = T(uniform());
        const T u0 = T(uniform());
        const LightSample<T> ls = lights.sample_point(u, Vec2<T>(u0, T(uniform())), pdf);
        const Vec3<T> d = ls.position - p.x;
        const T r2 = glm::dot(d, d);
        const Vec3<T> wi = d / std::sqrt(r2);
        const bool point = ls.normal == Vec3<T>(0);
        const T cos_l = point ? T(1) : -glm::dot(wi, ls.normal);
        const Vec3<T> wl = frame.to_local(wi);
        if (!(cos_l > T(0)) || wl.z <= T(0) || !(pdf > T(0))) continue;
        const Rgb<T> f = brdf.f(wl);
        if (f.max() <= T(0)) continue;
        const Ray<T> r0 = detail::vpl_spawn(p.x, p.n, wi);
        const Vec3<T> y = point ? ls.position : detail::vpl_spawn(ls.position, ls.normal, -wi).origin;
        if (accel.any_hit(Ray<T>{r0.origin, y - r0.origin, T(0), T(1) - T(1e-4)})) continue;
        sum += ls.power * f * (wl.z * cos_l / (r2 * pdf));
    }
    return sum * (p.weight / T(samples));
}

/// Sum over the VPLs of dPhi (kd_y / pi) w(wi) cos(theta_x) cos(theta_y) / max(r^2, d2min)
/// V(x, y) at point x (normal n), w(wi) = brdf(wi) (f_r for radiance, 1 for irradiance).
template <Scalar T, class V, class Brdf>
    requires VisibilityPolicy<V, T>
Rgb<T> vpl_sum(const Vec3<T>& x, const Vec3<T>& n, std::span<const Vpl<T>> vpls, V& vis, T d2min, const Brdf& brdf) {
    Rgb<T> sum(T(0));
    for (const Vpl<T>& v : vpls) {
        const Vec3<T> d = v.position - x;
        const T r2 = glm::dot(d, d);
        if (!(r2 > T(0))) continue;
        const Vec3<T> wi = d / std::sqrt(r2);
        const T cx = glm::dot(n, wi), cy = -glm::dot(v.normal, wi);
        if (cx <= T(0) || cy <= T(0)) continue;  // facing away: no contribution, no test
        const Rgb<T> f = brdf(wi);
        if (f.max() <= T(0) || !vis.visible(v.position)) continue;
        sum += v.power * v.albedo * f * (cx * cy / (std::max(r2, d2min) * pi<T>));
    }
    return sum;
}

/// Sum of the VPLs' illumination reflected at p towards the viewer (without p.weight),
/// visibility by policy `vis`; d2min is the squared clamp distance (0: unclamped).
template <Scalar T, class V>
    requires VisibilityPolicy<V, T>
Rgb<T> gather_point(const Scene<T>& s, const PixelPoint<T>& p, std::span<const Vpl<T>> vpls, V& vis, T d2min) {
    const Frame<T> frame = Frame<T>::from_normal(p.n);
    const SurfaceBrdf<T> brdf(s.materials[p.material], frame.to_local(p.wo));
    vis.set_point(p.x, p.n);
    return vpl_sum(p.x, p.n, vpls, vis, d2min, [&](const Vec3<T>& wi) { return brdf.f(frame.to_local(wi)); });
}

/// The camera's pixel points, row-major (one ray per pixel centre).
template <SceneAccelerator A, Scalar T = typename A::scalar_type>
std::vector<PixelPoint<T>> primary_points(const Scene<T>& s, const A& accel, const VplSettings& st) {
    st.validate();
    s.validate();
    std::vector<PixelPoint<T>> out(std::size_t(st.width) * std::size_t(st.height));
    detail::run_rows(st.height, st.threads, [&](std::atomic<int>& next) {
        for (int y = next++; y < st.height; y = next++)
            for (int x = 0; x < st.width; ++x) {
                Pcg32 rng = detail::pixel_rng(x, y, st.seed ^ 0xca11);
                out[std::size_t(y) * std::size_t(st.width) + std::size_t(x)] = primary_point(s, accel, x, y, st, rng);
            }
    });
    return out;
}

/// Emission seen directly plus direct illumination, per pixel point.
template <SceneAccelerator A, Scalar T = typename A::scalar_type>
std::vector<Rgb<T>> direct_image(const Scene<T>& s, const A& accel, std::span<const PixelPoint<T>> points,
                                 const VplSettings& st) {
    const EmitterSet<T> lights(s);
    std::vector<Rgb<T>> out(points.size(), Rgb<T>(T(0)));
    detail::run_rows(st.height, st.threads, [&](std::atomic<int>& next) {
        for (int y = next++; y < st.height; y = next++)
            for (int x = 0; x < st.width; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(st.width) + std::size_t(x);
                Pcg32 rng = detail::pixel_rng(x, y, st.seed);
                out[i] = points[i].emitted;
                if (points[i].hit)
                    out[i] += direct_light(s, accel, lights, points[i], st.light_samples, [&rng] { return rng.uniform<T>(); });
            }
    });
    return out;
}

/// The VPLs' illumination per pixel point (weighted by the camera path), one copy of the
/// visibility policy per thread.
template <Scalar T, class V>
    requires VisibilityPolicy<V, T>
std::vector<Rgb<T>> gather_image(const Scene<T>& s, std::span<const PixelPoint<T>> points, std::span<const Vpl<T>> vpls,
                                 const V& visibility, const VplSettings& st) {
    std::vector<Rgb<T>> out(points.size(), Rgb<T>(T(0)));
    const T d2min = T(st.min_distance * st.min_distance);
    detail::run_rows(st.height, st.threads, [&](std::atomic<int>& next) {
        V vis = visibility;
        for (int y = next++; y < st.height; y = next++)
            for (int x = 0; x < st.width; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(st.width) + std::size_t(x);
                if (points[i].hit) out[i] = gather_point(s, points[i], vpls, vis, d2min) * points[i].weight;
            }
    });
    return out;
}

/// The virtual light sources method as an Integrator (tracer/renderer.hpp) over VPLs shot
/// beforehand: for a camera ray, the emission it sees through mirrors and dielectrics, direct
/// illumination at the first diffuse or glossy point and the VPLs' illumination there through
/// the visibility policy (each rendering thread its own copy, thread_state). rays counts the
/// camera path's and the light samples' rays (the visibility policy's tests are its own). The
/// VPL part is kept per pixel and written by finish() to the film layer "indirect".
template <SceneAccelerator A, class V, Scalar T = typename A::scalar_type>
    requires VisibilityPolicy<V, T>
class VplIntegrator {
public:
    using scalar_type = T;
    using thread_state = V;
    struct pixel_state {
        Rgb<T> indirect{T(0)};  // sum of the samples' VPL parts
        std::uint32_t samples = 0;
    };

    /// `vpls` must outlive the integrator.
    VplIntegrator(const Scene<T>& s, const A& accel, std::span<const Vpl<T>> vpls, const V& visibility,
                  const VplSettings& st)
        : scene_(s), accel_(accel), lights_(s), vpls_(vpls), visibility_(visibility), st_(st),
          d2min_(T(st.min_distance * st.min_distance)) {
        st.validate();
    }

    V make_thread_state() const { return visibility_; }

    template <class S>
        requires Sampler<S, T>
    PathSample<T> radiance(const Ray<T>& ray, S& sampler, pixel_state& state, V& vis) const {
        const detail::CountedRays<A> accel(accel_);
        const auto uniform = [&sampler] { return sampler.get_1d(); };
        const PixelPoint<T> p = surface_seen(scene_, accel, ray, st_.max_specular, uniform);
        PathSample<T> out;
        if (st_.direct) {
            out.L = p.emitted;
            if (p.hit) out.L += direct_light(scene_, accel, lights_, p, st_.light_samples, uniform);
        }
        if (st_.indirect && p.hit) {
            const Rgb<T> indirect = gather_point(scene_, p, vpls_, vis, d2min_) * p.weight;
            if (indirect.is_finite()) state.indirect += indirect;
            out.L += indirect;
        }
        ++state.samples;
        out.rays = accel.rays();
        return out;
    }

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
    std::span<const Vpl<T>> vpls_;
    V visibility_;
    VplSettings st_;
    T d2min_;
};

/// What render_vpl returns: the renderer's result (image, variance, rays, seconds: shooting
/// included), the image's VPL part, and the shooting's count and time.
struct VplResult : RenderResult {
    Image<Rgb<float>> indirect;
    std::size_t vpls = 0;
    double shooting_seconds = 0;
};

/// The whole method: shooting with roulette R, then gathering through the Renderer with
/// visibility policy V, one camera ray per pixel through its centre.
template <SceneAccelerator A, class R, class V, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T> && VisibilityPolicy<V, T>
VplResult render_vpl(const Scene<T>& s, const A& accel, const R& roulette, const V& visibility, const VplSettings& st) {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    st.validate();
    s.validate();
    const std::vector<Vpl<T>> vpls =
        st.indirect ? shoot_scene_vpls(s, accel, roulette, st.vpl_walks, st.seed, st.shooting) : std::vector<Vpl<T>>{};
    VplResult out;
    out.shooting_seconds = std::chrono::duration<double>(clock::now() - t0).count();
    out.vpls = vpls.size();
    RenderSettings rs;
    rs.width = st.width, rs.height = st.height, rs.threads = st.threads;
    rs.spp = 1;
    rs.pixel_jitter = false;
    const VplIntegrator<A, V, T> integrator(s, accel, std::span<const Vpl<T>>(vpls), visibility, st);
    static_cast<RenderResult&>(out) = render_image(s, rs, integrator, RandomSampler<T>(st.seed));
    for (FilmLayer& layer : out.layers)
        if (layer.name == "indirect") out.indirect = std::move(layer.pixels);
    std::erase_if(out.layers, [](const FilmLayer& l) { return l.name == "indirect"; });
    out.seconds = std::chrono::duration<double>(clock::now() - t0).count();
    return out;
}

}  // namespace glint
