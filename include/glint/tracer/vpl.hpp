// glint/tracer/vpl.hpp: the virtual point light (instant radiosity) renderer of 000 section
// 1.4, with a pluggable visibility policy for the gathering phase (000 chapter 5).
//
// 000 section 1.4. Shooting: random walks start at a light sample z_0 with
// direction omega_0 and, with 000's reindexing of the walk, leave at every hit
// y = z_{n-1} a photon hit (virtual point light) of incoming power
//   dPhi_vpl = Le(z_0, omega_0) / p_light(z_0, omega_0) * prod_{i=1}^{n-2} w(omega_i, z_i, omega_{i-1}) / (p(omega_i, z_i) s(z_i))
// (the extraction lost the fraction bars and product limits; repaired from Fig. 1.5 and the
// definitions below the formula: p_light and p are the light-sample and direction densities,
// s(z_i) the continuation probability, w = f_r cos). Walks continue by a roulette policy of
// sampling/roulette.hpp (RoulettePolicy) through scatter() with the Lambertian material of
// tracer/brdf.hpp, so w / (p s) = albedo / s. Gathering: a shading point x seen through a pixel
// is connected deterministically to every VPL y; for diffuse surfaces
//   L(x) = sum_vpl f_r(x) dPhi f_r(y) cos(theta_x) cos(theta_y) / |x - y|^2 * V(x, y)
// with f_r = albedo / pi. The squared distance is clamped below by min_distance^2 (the usual
// VPL clamp; it is the same for every visibility policy, so comparisons stay fair).
// V is a VisibilityPolicy: ShadowRayVisibility (exact shadow rays through a trees/
// accelerator) or the occluder-sphere searches of occluders/visibility.hpp.
// The renderer gathers VPL light only (indirect illumination and the first bounce of the
// light's emission); directly seen emission is left out, as in 000's Fig. 5.7 measurements.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// Diffuse triangles with per-triangle albedo and emitted radiance.
template <Scalar T>
struct VplScene {
    std::vector<TriangleVertices<T>> triangles;
    std::vector<Rgb<T>> albedo;    // per triangle, in [0, 1)
    std::vector<Rgb<T>> emission;  // per triangle radiance Le (zero for non-emitters)

    void add(std::span<const TriangleVertices<T>> tris, const Rgb<T>& a, const Rgb<T>& le = Rgb<T>(T(0))) {
        for (const auto& t : tris) {
            triangles.push_back(t);
            albedo.push_back(a);
            emission.push_back(le);
        }
    }
    void validate() const {
        if (albedo.size() != triangles.size() || emission.size() != triangles.size())
            throw Error("glint::VplScene: albedo and emission need one entry per triangle");
        for (std::size_t i = 0; i < albedo.size(); ++i)
            for (std::size_t c = 0; c < 3; ++c)
                if (!(albedo[i][c] >= T(0) && albedo[i][c] < T(1)) || !(emission[i][c] >= T(0)) ||
                    !std::isfinite(emission[i][c]))
                    throw Error("glint::VplScene: triangle " + std::to_string(i) +
                                " needs albedo in [0, 1) and finite non-negative emission");
    }
};

template <Scalar T>
struct Vpl {
    Vec3<T> position{0};
    Vec3<T> normal{0, 0, 1};  // facing the side the light arrived from
    Rgb<T> power{};           // incoming power dPhi
    Rgb<T> albedo{};
};

/// Exact visibility: a shadow ray through a RayAccelerator (trees/ kd-tree, BIH, brute force).
template <RayAccelerator Accel>
class ShadowRayVisibility {
public:
    using T = typename Accel::scalar_type;
    ShadowRayVisibility(const Accel& accel, T epsilon) : accel_(&accel), eps_(epsilon) {}
    void set_point(const Vec3<T>& x, const Vec3<T>& n) { x_ = x + eps_ * n; }
    bool visible(const Vec3<T>& y) const {
        Ray<T> r;
        r.origin = x_;
        r.direction = y - x_;
        r.tmin = T(0);
        r.tmax = T(1) - eps_;  // in units of |y - x|; y itself is on a surface
        return !accel_->any_hit(r);
    }

private:
    const Accel* accel_;
    T eps_;
    Vec3<T> x_{0};
};

namespace detail {

template <class T>
Vec3<T> triangle_normal(const TriangleVertices<T>& t) {
    return safe_normalize(glm::cross(t[1] - t[0], t[2] - t[0]));
}

}  // namespace detail

/// Shooting phase: `walks` random walks from the emitters (area-weighted by emitted
/// luminance, cosine-distributed directions), continued by roulette R; returns the VPLs.
template <Scalar T, RayAccelerator Accel, RoulettePolicy<T, 3> R>
std::vector<Vpl<T>> shoot_vpls(const VplScene<T>& scene, const Accel& accel, const R& roulette, std::size_t walks,
                               std::uint64_t seed, std::size_t max_depth = 16) {
    scene.validate();
    std::vector<double> cdf;
    double total = 0;
    for (std::size_t i = 0; i < scene.triangles.size(); ++i) {
        const auto& t = scene.triangles[i];
        const double area = 0.5 * glm::length(glm::cross(Vec3d(t[1] - t[0]), Vec3d(t[2] - t[0])));
        total += area * double(scene.emission[i].luminance());
        cdf.push_back(total);
    }
    if (!(total > 0)) throw Error("glint::shoot_vpls: the scene has no emitting triangle");
    std::vector<Vpl<T>> out;
    Pcg32 rng(seed, 5);
    const T eps = T(1e-4);
    for (std::size_t w = 0; w < walks; ++w) {
        const double x = rng.uniform<double>() * total;
        const auto li = std::min<std::size_t>(std::size_t(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin()),
                                              cdf.size() - 1);
        const auto& lt = scene.triangles[li];
        Vec3<T> p = sample_triangle(lt[0], lt[1], lt[2], Vec2<T>(rng.uniform<T>(), rng.uniform<T>()));
        Vec3<T> n = detail::triangle_normal(lt);
        const double area = 0.5 * glm::length(glm::cross(Vec3d(lt[1] - lt[0]), Vec3d(lt[2] - lt[0])));
        const double p_area = (area * double(scene.emission[li].luminance()) / total) / area;
        // Le cos / (p_area * cos / pi) = Le pi / p_area, per walk.
        Rgb<T> power = scene.emission[li] * T(pi<double> / p_area / double(walks));  // one-sided: along the
                                                                                    // geometric normal
        Vec3<T> dir = Frame<T>::from_normal(n).to_world(
            square_to_cosine_hemisphere(Vec2<T>(rng.uniform<T>(), rng.uniform<T>())));
        for (std::size_t depth = 0; depth < max_depth; ++depth) {
            Ray<T> ray;
            ray.origin = p + eps * n;
            ray.direction = dir;
            StoreHit<T> hit;
            if (!accel.closest_hit(ray, hit)) break;
            const auto& tri = scene.triangles[hit.id];
            p = ray.at(hit.t);
            n = detail::triangle_normal(tri);
            if (glm::dot(n, dir) > 0) n = -n;
            const Rgb<T> a = scene.albedo[hit.id];
            out.push_back({p, n, power, a});
            const SurfaceBrdf<T> brdf(Material<T>::lambertian(a), Vec3<T>(0, 0, 1));
            const ScatterSample<T, 3> s = scatter(
                brdf, roulette, power, rng.uniform<T>(), Vec2<T>(rng.uniform<T>(), rng.uniform<T>()), int(depth),
                BrdfSelection::decomposition);
            if (s.terminated()) break;
            power = power * s.weight;
            dir = Frame<T>::from_normal(n).to_world(s.direction);
        }
    }
    return out;
}

/// A pinhole camera looking from `eye` at `target`.
template <Scalar T>
struct PinholeCamera {
    Vec3<T> eye{0, 0, 5}, target{0}, up{0, 1, 0};
    T fov_y = T(0.8);  // radians
    int width = 64, height = 64;

    Ray<T> ray(int px, int py) const {
        const Vec3<T> f = safe_normalize(target - eye), r = safe_normalize(glm::cross(f, up)), u = glm::cross(r, f);
        const T th = std::tan(fov_y / 2), aspect = T(width) / T(height);
        const T sx = (T(2) * (T(px) + T(0.5)) / T(width) - T(1)) * th * aspect;
        const T sy = (T(1) - T(2) * (T(py) + T(0.5)) / T(height)) * th;
        Ray<T> out;
        out.origin = eye;
        out.direction = safe_normalize(f + sx * r + sy * u);
        return out;
    }
};

/// Gathering phase: one primary ray per pixel, every VPL connected through visibility policy
/// V. Returns width * height RGB values (row-major). `vis` is used by this thread only.
template <Scalar T, RayAccelerator Accel, class V>
    requires VisibilityPolicy<V, T>
std::vector<Rgb<T>> gather_vpls(const VplScene<T>& scene, const Accel& accel, std::span<const Vpl<T>> vpls,
                                const PinholeCamera<T>& cam, V& vis, T min_distance) {
    std::vector<Rgb<T>> img(std::size_t(cam.width) * std::size_t(cam.height), Rgb<T>(T(0)));
    const T inv_pi = T(1) / pi<T>, d2min = min_distance * min_distance;
    for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
            const Ray<T> ray = cam.ray(x, y);
            StoreHit<T> hit;
            if (!accel.closest_hit(ray, hit)) continue;
            const Vec3<T> p = ray.at(hit.t);
            Vec3<T> n = detail::triangle_normal(scene.triangles[hit.id]);
            if (glm::dot(n, ray.direction) > 0) n = -n;
            vis.set_point(p, n);
            Rgb<T> sum(T(0));
            for (const auto& v : vpls) {
                const Vec3<T> d = v.position - p;
                const T dist2 = glm::dot(d, d);
                const T cx = glm::dot(n, d), cy = -glm::dot(v.normal, d);
                if (cx <= T(0) || cy <= T(0)) continue;  // facing away: no contribution, no test
                if (!vis.visible(v.position)) continue;
                const T g = cx * cy / (dist2 * std::max(dist2, d2min));
                sum += v.power * v.albedo * g;
            }
            img[std::size_t(y) * std::size_t(cam.width) + std::size_t(x)] = sum * scene.albedo[hit.id] * (inv_pi * inv_pi);
        }
    return img;
}

/// Relative RMSE of `img` against `ref` over all pixels and channels:
/// sqrt(sum (img - ref)^2 / sum ref^2).
template <Scalar T>
double relative_rmse(std::span<const Rgb<T>> img, std::span<const Rgb<T>> ref) {
    if (img.size() != ref.size()) throw Error("glint::relative_rmse: images differ in size");
    double num = 0, den = 0;
    for (std::size_t i = 0; i < img.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            const double e = double(img[i][c]) - double(ref[i][c]);
            num += e * e;
            den += double(ref[i][c]) * double(ref[i][c]);
        }
    return den > 0 ? std::sqrt(num / den) : 0.0;
}

}  // namespace glint
