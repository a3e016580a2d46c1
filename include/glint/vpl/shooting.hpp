// glint/vpl/shooting.hpp: the shooting phase of the virtual light sources method over the
// ordinary Scene (area and point lights, the path tracer's materials); Keller 1997, instant
// radiosity, as Szécsi 2009, §1.4 presents it.
//
// A shooting walk starts at a light sample z_0 with direction omega_0 and leaves at every
// non-specular hit y a virtual point light (VPL) of incoming power
//   dPhi = Le(z_0, omega_0) / p_light(z_0, omega_0) * prod w / (p s)
// (Szécsi 2009, §1.4 and its Fig. 1.5: p_light and p are the light-sample and direction
// densities, s the continuation probability, w = f_r cos; the formula's fraction bars and
// product limits are repaired from the figure). Emitters are chosen by power: an area-light
// triangle (uniform point, cosine direction: dPhi = pi Le A_k / P_k) or a point light
// (uniform direction: dPhi = 4 pi I / P_k), P_k the emitter's selection probability. The
// walk goes on through scatter() with the hit material's own BRDF (SurfaceBrdf: diffuse and
// Phong lobes) under a roulette policy; mirrors and dielectrics are followed
// deterministically (Fresnel choice for dielectrics) and leave no VPL. A VPL reflects
// diffusely towards the gathering point (f_r(y) = kd / pi, the diffuse estimator of Szécsi
// 2009, §1.4; its general form would evaluate f_r(y) with the stored incoming direction,
// which glint does not), so glossy light transport through a VPL is the method's
// approximation; for Lambertian scenes the method is unbiased.
#pragma once

#include <algorithm>
#include <array>
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
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/light_walk.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// A virtual point light: where a shooting walk hit a non-specular surface, with the power
/// that arrived there.
template <Scalar T>
struct Vpl {
    Vec3<T> position{0};      ///< The hit point, world space.
    Vec3<T> normal{0, 0, 1};  ///< Unit surface normal facing the side the light arrived from
    Rgb<T> power{};           ///< incoming power dPhi (from shoot_scene_vpls: the estimator's 1 / walks included)
    Rgb<T> albedo{};          ///< kd at the hit: the VPL reflects kd / pi
};

/// A roulette policy that a shooting walk can use (a radiance estimate's offset is reflected
/// radiance, which a walk carrying power has no use for: shooting walks ignore it).
template <class R, class T>
concept ShootingRoulette = RoulettePolicy<R, T, 3>;

/// Where a light sample leaves from: position, direction, and power / density.
template <Scalar T>
struct LightSample {
    Vec3<T> position{0};  ///< Point on the emitter, world space.
    Vec3<T> normal{0};  ///< Unit normal of an area light; zero for a point light
    Vec3<T> direction{0, 0, 1};  ///< Unit emission direction (EmitterSet::sample; unset by sample_point)
    Rgb<T> power{};  ///< Power / density of the sample (sample), or Le or I of the emitter (sample_point)
    const PointLight<T>* light = nullptr;  ///< the point light sampled (its profile), else null

    /// What leaves towards unit direction w: `power`, through a point light's profile.
    Rgb<T> towards(const Vec3<T>& w) const { return light ? light->intensity_towards(w) : power; }
};

/// The scene's emitters (area-light triangles and point lights), chosen by luminance power.
template <Scalar T>
class EmitterSet {
public:
    /// Collects the emissive triangles of positive area and the point lights of `s` (validated
    /// first). Throws Error when the scene has no light that emits. Allocates.
    explicit EmitterSet(const Scene<T>& s) {
        s.validate();
        for (std::size_t i = 0; i < s.triangles.size(); ++i) {
            const Material<T>& m = s.materials[s.material_of[i]];
            if (!m.emissive()) continue;
            const auto& t = s.triangles[i];
            const T area = triangle_area(t[0], t[1], t[2]);
            if (area > T(0)) add({t[0], t[1], t[2]}, s.normal(i), m.emission, area, pi<T> * area);
        }
        for (const auto& p : s.point_lights)
            if (p.intensity.max() > T(0)) add({p.position, p.position, p.position}, Vec3<T>(0), p.intensity, T(0), p.measure(), &p);
        if (!(total_ > T(0))) throw Error("glint::EmitterSet: scene '" + s.name + "' has no light that emits");
    }

    /// One light sample from three independent uniforms (emitter, position, direction).
    LightSample<T> sample(T u, const Vec2<T>& u_pos, const Vec2<T>& u_dir) const {
        const std::size_t k = pick(u);
        const Emitter& e = emitters_[k];
        const T prob = probability(k);
        LightSample<T> out;
        if (e.area > T(0)) {
            out.position = sample_triangle(e.v[0], e.v[1], e.v[2], u_pos);
            out.normal = e.normal;
            out.direction = Frame<T>::from_normal(e.normal).to_world(square_to_cosine_hemisphere(u_dir));
        } else {
            out.position = e.v[0];
            out.direction = square_to_uniform_sphere(u_dir);
            out.light = e.point;
        }
        // A point light's direction is uniform on the sphere (density 1 / 4 pi), whatever its profile.
        out.power = e.area > T(0) ? e.radiance * (e.measure / prob) : e.point->intensity_towards(out.direction) * (T(4) * pi<T> / prob);
        return out;
    }

    /// A point of an emitter for direct illumination (emitter by power, uniform on an area
    /// light): radiance Le (or intensity I), normal (zero for a point light) and the density
    /// (area density P_k / A_k on an area light, the probability P_k for a point light).
    LightSample<T> sample_point(T u, const Vec2<T>& u_pos, T& pdf) const {
        const std::size_t k = pick(u);
        const Emitter& e = emitters_[k];
        LightSample<T> out;
        out.position = e.area > T(0) ? sample_triangle(e.v[0], e.v[1], e.v[2], u_pos) : e.v[0];
        out.normal = e.area > T(0) ? e.normal : Vec3<T>(0);
        out.power = e.radiance;
        out.light = e.point;
        pdf = e.area > T(0) ? probability(k) / e.area : probability(k);
        return out;
    }

    /// Total luminance power of the emitters (pi Le A for area lights, PointLight::power()).
    T total_power() const { return total_; }

private:
    struct Emitter {
        std::array<Vec3<T>, 3> v;
        Vec3<T> normal;
        Rgb<T> radiance;  // Le, or I for a point light
        T area;           // 0: point light
        T measure;        // pi A, or a point light's measure(): power = radiance * measure
        const PointLight<T>* point;  // the scene's point light, else null
    };
    void add(const std::array<Vec3<T>, 3>& v, const Vec3<T>& n, const Rgb<T>& le, T area, T measure,
             const PointLight<T>* point = nullptr) {
        emitters_.push_back({v, n, le, area, measure, point});
        total_ += le.luminance() * measure;
        cdf_.push_back(total_);
    }
    std::size_t pick(T u) const {
        const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u * total_);
        return std::min<std::size_t>(std::size_t(it - cdf_.begin()), cdf_.size() - 1);
    }
    T probability(std::size_t k) const { return (cdf_[k] - (k ? cdf_[k - 1] : T(0))) / total_; }

    std::vector<Emitter> emitters_;
    std::vector<T> cdf_;
    T total_ = 0;
};

/// Options of the shooting phase (path splitting is an option of the path trees:
/// AnimationOptions::branches, LightPathMapOptions::branches).
struct ShootingOptions {
    int max_depth = 1024;  ///< cap on a walk's vertices (>= 1), far beyond where roulette stops walks
};

/// Follows one shooting walk from `ray` carrying `power` (the first hit's incoming power),
/// appending a VPL at each non-specular hit; roulette decides on the normalized throughput.
/// `first_depth` counts the scattering vertices before the ray (for the roulette).
template <RayAccelerator A, class R, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T>
void trace_shooting_walk(const Scene<T>& s, const A& accel, const R& roulette, Ray<T> ray, const Rgb<T>& power,
                         Pcg32& rng, int max_depth, std::vector<Vpl<T>>& out, int first_depth = 0) {
    light_walk(s, accel, roulette, ray, power, rng, max_depth, first_depth, [&](const LightWalkVertex<T>& v) {
        if (v.material->kd.max() > T(0)) out.push_back({v.x, v.n, v.power, v.material->kd});
    });
}

/// A path tree from a Lambertian point z1 (normal n1 on the lit side, material m) that
/// received `power`: the VPL at z1, then `branches` walks leaving z1, each with 1 / branches
/// of the power (the splitting of Szécsi 2009, §7.2.1; the N_s paths per entry point of §8.1.4).
template <RayAccelerator A, class R, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T>
void shoot_path_tree(const Scene<T>& s, const A& accel, const R& roulette, const Vec3<T>& z1, const Vec3<T>& n1,
                     const Material<T>& m, const Rgb<T>& power, int branches, Pcg32& rng, int max_depth,
                     std::vector<Vpl<T>>& out) {
    if (!(power.max() > T(0))) return;
    if (m.kd.max() > T(0)) out.push_back({z1, n1, power, m.kd});
    const Frame<T> frame = Frame<T>::from_normal(n1);
    const SurfaceBrdf<T> brdf(m, Vec3<T>(0, 0, 1));  // Lambertian: the incoming direction does not matter
    const Rgb<T> beta = power / power.max();
    for (int b = 0; b < branches; ++b) {
        const T u_sel = rng.uniform<T>();
        const Vec2<T> u_dir(rng.uniform<T>(), rng.uniform<T>());
        const ScatterSample<T, 3> step = scatter(brdf, roulette, beta, u_sel, u_dir, 0);
        if (step.terminated()) continue;
        trace_shooting_walk(s, accel, roulette, detail::light_spawn(z1, n1, frame.to_world(step.direction)),
                            power * step.weight / T(branches), rng, max_depth, out, 1);
    }
}

/// Shooting phase: `walks` walks from the scene's emitters (chosen by power), stream `seed`.
/// Each VPL's power already carries the 1 / walks of the estimator.
template <RayAccelerator A, class R, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T>
std::vector<Vpl<T>> shoot_scene_vpls(const Scene<T>& s, const A& accel, const R& roulette, std::size_t walks,
                                     std::uint64_t seed, const ShootingOptions& opt = {}) {
    if (walks == 0) throw Error("glint::shoot_scene_vpls: walks must be positive (got 0)");
    if (opt.max_depth < 1) throw Error("glint::shoot_scene_vpls: max_depth " + std::to_string(opt.max_depth) + " < 1");
    const EmitterSet<T> emitters(s);
    std::vector<Vpl<T>> out;
    Pcg32 rng(seed, 0x5eed);
    for (std::size_t w = 0; w < walks; ++w) {
        const T u = rng.uniform<T>();
        const Vec2<T> up(rng.uniform<T>(), rng.uniform<T>()), ud(rng.uniform<T>(), rng.uniform<T>());
        const LightSample<T> ls = emitters.sample(u, up, ud);
        const Ray<T> ray = ls.normal == Vec3<T>(0) ? Ray<T>{ls.position, ls.direction, T(0), infinity<T>}
                                                   : detail::light_spawn(ls.position, ls.normal, ls.direction);
        trace_shooting_walk(s, accel, roulette, ray, ls.power / T(walks), rng, opt.max_depth, out);
    }
    return out;
}

}  // namespace glint
