// glint/vpl/integrator.hpp: the virtual light sources method as an integrator over the
// ordinary Scene: shooting (vpl/shooting.hpp), then gathering at the points the camera sees.
//
// 000 section 1.4 (lines 860-945), gathering: a shading point x seen through a pixel (after
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
// One camera ray per pixel, through the pixel centre. Rows are gathered in parallel with
// std::thread; every thread has its own copy of the visibility policy; a pixel's random
// numbers come from a stream of its own, so images do not depend on the thread count.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
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
#include <glint/tracer/brdf.hpp>
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

namespace detail {

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
    return Pcg32(seed * 0x9e3779b97f4a7c15ULL + 0x51ed, (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x));
}

}  // namespace detail

/// Follows the camera ray of pixel (px, py) through mirrors and dielectrics to the first
/// diffuse or glossy point.
template <SceneAccelerator A, Scalar T = typename A::scalar_type>
PixelPoint<T> primary_point(const Scene<T>& s, const A& accel, int px, int py, const VplSettings& st, Pcg32& rng) {
    const T aspect = T(st.width) / T(st.height);
    Ray<T> ray = s.camera.ray((T(px) + T(0.5)) / T(st.width), (T(py) + T(0.5)) / T(st.height), aspect);
    PixelPoint<T> p;
    p.weight = Rgb<T>(T(1));
    p.emitted = Rgb<T>(T(0));
    for (int k = 0; k <= st.max_specular; ++k) {
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
        ray = detail::vpl_spawn(x, n, specular_direction(m, d, ng, rng.uniform<T>()));
    }
    return p;
}

/// Direct illumination at p from `samples` real-light samples (shadow rays through accel).
template <SceneAccelerator A, Scalar T = typename A::scalar_type>
Rgb<T> direct_light(const Scene<T>& s, const A& accel, const EmitterSet<T>& lights, const PixelPoint<T>& p,
                    int samples, Pcg32& rng) {
    const Frame<T> frame = Frame<T>::from_normal(p.n);
    const SurfaceBrdf<T> brdf(s.materials[p.material], frame.to_local(p.wo));
    Rgb<T> sum(T(0));
    for (int i = 0; i < samples; ++i) {
        T pdf;
        const T u = rng.uniform<T>();
        const LightSample<T> ls = lights.sample_point(u, Vec2<T>(rng.uniform<T>(), rng.uniform<T>()), pdf);
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
                if (points[i].hit) out[i] += direct_light(s, accel, lights, points[i], st.light_samples, rng);
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

/// What render_vpl returns: the image, its indirect (VPL) part, and what it cost.
struct VplResult {
    Image<Rgb<float>> image, indirect;
    std::size_t vpls = 0;
    double seconds = 0, shooting_seconds = 0;
};

/// The whole method: shooting with roulette R, then gathering with visibility policy V.
template <SceneAccelerator A, class R, class V, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T> && VisibilityPolicy<V, T>
VplResult render_vpl(const Scene<T>& s, const A& accel, const R& roulette, const V& visibility, const VplSettings& st) {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    st.validate();
    VplResult out{Image<Rgb<float>>(st.width, st.height), Image<Rgb<float>>(st.width, st.height)};
    const std::vector<Vpl<T>> vpls =
        st.indirect ? shoot_scene_vpls(s, accel, roulette, st.vpl_walks, st.seed, st.shooting) : std::vector<Vpl<T>>{};
    out.shooting_seconds = std::chrono::duration<double>(clock::now() - t0).count();
    out.vpls = vpls.size();
    const auto points = primary_points(s, accel, st);
    std::vector<Rgb<T>> direct(points.size(), Rgb<T>(T(0))), indirect(points.size(), Rgb<T>(T(0)));
    if (st.direct) direct = direct_image(s, accel, std::span<const PixelPoint<T>>(points), st);
    if (st.indirect) indirect = gather_image(s, std::span<const PixelPoint<T>>(points), std::span<const Vpl<T>>(vpls), visibility, st);
    for (std::size_t i = 0; i < points.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            out.indirect.pixels[i][c] = float(indirect[i][c]);
            out.image.pixels[i][c] = float(direct[i][c] + indirect[i][c]);
        }
    out.seconds = std::chrono::duration<double>(clock::now() - t0).count();
    return out;
}

}  // namespace glint
