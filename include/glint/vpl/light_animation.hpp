// glint/vpl/light_animation.hpp: light animation with path reuse (Szécsi 2009, ch. 7):
// a small light moves through F frames of a static scene; every frame's shooting
// paths are reused in every frame by connecting their first hit z_1 to that frame's light
// (Sbert, Szécsi and Szirmay-Kalos 2004; the balance heuristic of Veach and Guibas 1995).
//
// Szécsi 2009, §7.1 (eq. 7.1). The path z^(f) = (z^(f), z_1, z_2, ...) shot
// in frame f is, in frame i, the path (z^(i), z_1, z_2, ...). With N paths per frame and the
// balance heuristic over the F frames' sampling techniques, its weight in frame i is
//   alpha^(i) = p^(i)(z^(i), z_1, z_2, ...) / sum_{j=1..F} p^(j)(z^(j), z_1, z_2, ...),
// p^(j) the density of generating the path in frame j. (The extraction lost the fraction
// bar and put the summation limits and superscripts on separate lines; repaired from the
// surrounding text: "the weight ... proportional to this probability", normalized over the
// frames.) Only the first segment differs between the frames, so every later factor cancels
// (Szécsi 2009, §7.2): p^(j) reduces to the density of z_1 as a first hit from z^(j),
//   q_j = p_light(omega_{z^(j) -> z_1}) xi(z^(j) -> z_1),  xi = V cos(theta_{z_1}) / |z^(j) - z_1|^2
// (the repaired second formula of section 7.2; p(omega_1, z_1) is common to all frames and
// cancels). glint's point light emits uniformly (p_light = 1 / 4 pi). The frame-i estimate of
// the path's contribution f^(i) / (N sum_j p^(j)) then equals alpha^(i) times the path's own
// estimate in frame f with first-hit power 4 pi I / N (same intensity I in every frame), so the
// image of each path is computed once and frame i's indirect illumination is the
// alpha^(i)-weighted sum of all paths' images. For every path the weights
// sum to 1 over the frames (the own frame has q_f > 0), which makes the combination unbiased.
// Reuse needs the continuation from z_1 to be independent of where the light is: glint reuses
// a path only when z_1 is Lambertian (VPL reflection and the continuation's w / p = kd do not
// depend on the incoming direction); a path whose first hit is glossy or specular keeps weight
// 1 in its own frame and 0 elsewhere (a partition of path space by the first hit's material,
// the same in every frame, so the estimator stays unbiased).
// Section 7.2.1 (path splitting): `branches` continuations leave z_1, each with 1 / branches
// of the power: one image per path tree. Section 7.3 (on-line): frame i combines only the
// paths of frames i - W + 1 .. i, the balance heuristic running over those W frames.
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
#include <glint/vpl/gather.hpp>
#include <glint/vpl/shooting.hpp>

namespace glint {

/// Density of z1 (normal n1, facing the side the path arrived from) as the first hit of a
/// uniformly emitting point light at `light`, without visibility: cos(theta_1) / (4 pi r^2).
template <Scalar T>
T point_source_density(const Vec3<T>& light, const Vec3<T>& z1, const Vec3<T>& n1) {
    const Vec3<T> d = light - z1;
    const T r2 = glm::dot(d, d);
    const T c = glm::dot(n1, d);
    if (!(r2 > T(0)) || !(c > T(0))) return T(0);
    return c / (std::sqrt(r2) * r2) / (T(4) * pi<T>);
}

/// Balance-heuristic weights alpha_i = q_i / sum_j q_j (Szécsi 2009, eq. 7.1, repaired); all zero when
/// every q_j is zero. Throws when the sizes differ or a density is negative or not finite.
template <Scalar T>
void balance_weights(std::span<const T> q, std::span<T> alpha) {
    if (q.size() != alpha.size())
        throw Error("glint::balance_weights: " + std::to_string(q.size()) + " densities but " +
                    std::to_string(alpha.size()) + " weights");
    T sum = 0;
    for (std::size_t j = 0; j < q.size(); ++j) {
        if (!(q[j] >= T(0)) || !std::isfinite(q[j]))
            throw Error("glint::balance_weights: density " + std::to_string(j) + " is " + std::to_string(q[j]));
        sum += q[j];
    }
    for (std::size_t j = 0; j < q.size(); ++j) alpha[j] = sum > T(0) ? q[j] / sum : T(0);
}

/// One shooting path (or path tree) of an animation: its frame, its first hit and its VPLs
/// (powers of its own frame's estimate).
template <Scalar T>
struct AnimationPath {
    std::uint32_t frame = 0;  ///< The frame whose light position shot the path.
    /// First hit z_1, world space (zero when the light's ray hit nothing).
    Vec3<T> z1{0}, n1{0};  ///< Unit normal at z_1 facing the light (zero when nothing was hit).
    bool reusable = false;  ///< z1 Lambertian: the path is valid in every frame that sees z1
    std::vector<Vpl<T>> vpls;  ///< The path's VPLs, z_1's first, powers of its own frame's estimate.
};

/// Settings of shoot_light_animation.
struct AnimationOptions {
    std::size_t paths_per_frame = 1;  ///< Paths N shot from each frame's light position (> 0).
    int branches = 1;            ///< continuations from the first hit (Szécsi 2009, §7.2.1; >= 1)
    bool dependent = false;      ///< the same random numbers in every frame ("dependent sampling", Szécsi 2009, §7.2)
    std::uint64_t seed = 1;      ///< Seed of the paths' random streams.
    ShootingOptions shooting{};  ///< Walk depth cap (its max_depth only).
};

/// Shoots one path from the point light at `light` with first-hit power `power`.
template <RayAccelerator A, class R, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T>
AnimationPath<T> shoot_animation_path(const Scene<T>& s, const A& accel, const R& roulette, const Vec3<T>& light,
                                      const Rgb<T>& power, Pcg32& rng, const AnimationOptions& opt) {
    AnimationPath<T> p;
    const Vec2<T> u(rng.uniform<T>(), rng.uniform<T>());
    const Ray<T> ray{light, square_to_uniform_sphere(u), T(0), infinity<T>};
    StoreHit<T> hit;
    if (!accel.closest_hit(ray, hit)) return p;
    const Material<T>& m = s.materials[s.material_of[hit.id]];
    const Vec3<T> ng = s.normal(hit.id);
    p.z1 = ray.at(hit.t);
    p.n1 = glm::dot(ng, ray.direction) < T(0) ? ng : -ng;
    if (m.kind != MaterialKind::lambertian) {
        trace_shooting_walk(s, accel, roulette, ray, power, rng, opt.shooting.max_depth, p.vpls);
        return p;
    }
    p.reusable = true;
    shoot_path_tree(s, accel, roulette, p.z1, p.n1, m, power, opt.branches, rng, opt.shooting.max_depth, p.vpls);
    return p;
}

/// A light animation's shooting paths, their connection densities and (after
/// render_path_images) one indirect-illumination image per path.
template <Scalar T>
struct LightAnimation {
    std::vector<Vec3<T>> positions;           ///< the light, per frame
    std::vector<AnimationPath<T>> paths;      ///< frame-major, paths_per_frame per frame
    std::vector<T> density;                   ///< paths x frames: q_j with visibility (0 for paths not reusable)
    std::vector<std::vector<Rgb<T>>> images;  ///< per path (empty before render_path_images)
    std::size_t paths_per_frame = 1;          ///< Paths shot per frame, N.

    /// Number of frames F (light positions).
    std::size_t frames() const { return positions.size(); }

    /// Weight alpha^(i) of path s in frame i when frames lo..hi (containing i and the path's
    /// frame) are combined; 0 for a path outside them.
    T weight(std::size_t s, std::size_t i, std::size_t lo, std::size_t hi) const {
        const AnimationPath<T>& p = paths[s];
        if (p.frame < lo || p.frame > hi) return T(0);
        if (!p.reusable) return i == p.frame ? T(1) : T(0);
        const T* q = &density[s * frames()];
        T sum = 0;
        for (std::size_t j = lo; j <= hi; ++j) sum += q[j];
        return sum > T(0) ? q[i] / sum : T(0);
    }

    /// Frame i's indirect illumination: window 0 combines all frames (off-line, Szécsi 2009,
    /// §7.2); window W > 0 only frames i - W + 1 .. i (on-line, §7.3).
    std::vector<Rgb<T>> frame_image(std::size_t i, std::size_t window = 0) const {
        if (i >= frames()) throw Error("glint::LightAnimation: frame " + std::to_string(i) + " of " + std::to_string(frames()));
        if (images.size() != paths.size()) throw Error("glint::LightAnimation: render_path_images first");
        const std::size_t lo = window == 0 ? 0 : (i + 1 > window ? i + 1 - window : 0);
        const std::size_t hi = window == 0 ? frames() - 1 : i;
        std::vector<Rgb<T>> out(images.empty() ? 0 : images[0].size(), Rgb<T>(T(0)));
        for (std::size_t s = 0; s < paths.size(); ++s) {
            const T a = weight(s, i, lo, hi);
            if (a > T(0))
                for (std::size_t k = 0; k < out.size(); ++k) out[k] += images[s][k] * a;
        }
        return out;
    }
};

/// Shooting: paths_per_frame paths from each frame's light position (intensity I, uniform
/// emission), then each reusable path's density q_j in every frame, visibility by a shadow
/// ray from the frame's light to z1 (F connection rays per path; the own frame's is known).
template <RayAccelerator A, class R, Scalar T = typename A::scalar_type>
    requires ShootingRoulette<R, T>
LightAnimation<T> shoot_light_animation(const Scene<T>& s, const A& accel, const R& roulette,
                                        std::span<const Vec3<T>> positions, const Rgb<T>& intensity,
                                        const AnimationOptions& opt) {
    if (positions.empty() || opt.paths_per_frame == 0 || opt.branches < 1)
        throw Error("glint::shoot_light_animation: " + std::to_string(positions.size()) + " frames, " +
                    std::to_string(opt.paths_per_frame) + " paths per frame, " + std::to_string(opt.branches) +
                    " branches: all must be positive");
    LightAnimation<T> a;
    a.positions.assign(positions.begin(), positions.end());
    a.paths_per_frame = opt.paths_per_frame;
    const Rgb<T> power = intensity * (T(4) * pi<T> / T(opt.paths_per_frame));
    for (std::size_t f = 0; f < positions.size(); ++f)
        for (std::size_t k = 0; k < opt.paths_per_frame; ++k) {
            Pcg32 rng = Pcg32::hashed(opt.seed, opt.dependent ? k : f * opt.paths_per_frame + k);
            a.paths.push_back(shoot_animation_path(s, accel, roulette, positions[f], power, rng, opt));
            a.paths.back().frame = std::uint32_t(f);
        }
    const std::size_t F = positions.size();
    a.density.assign(a.paths.size() * F, T(0));
    for (std::size_t p = 0; p < a.paths.size(); ++p) {
        const AnimationPath<T>& path = a.paths[p];
        if (!path.reusable) continue;
        const Vec3<T> end = detail::light_spawn(path.z1, path.n1, path.n1).origin;
        for (std::size_t j = 0; j < F; ++j) {
            const T q = point_source_density(positions[j], path.z1, path.n1);
            const bool own = j == path.frame;
            if (q > T(0) && (own || !accel.any_hit(Ray<T>{positions[j], end - positions[j], T(0), T(1)})))
                a.density[p * F + j] = q;
        }
    }
    return a;
}

/// The indirect-illumination image of every path, gathered at `points` (primary_points)
/// with visibility V, the geometry term clamped at min_distance (0: unclamped).
template <Scalar T, class V>
    requires VisibilityPolicy<V, T>
void render_path_images(LightAnimation<T>& a, const Scene<T>& s, std::span<const PixelPoint<T>> points,
                        const V& visibility, double min_distance, int threads) {
    a.images.clear();
    for (const AnimationPath<T>& p : a.paths)
        a.images.push_back(gather_image(s, points, std::span<const Vpl<T>>(p.vpls), visibility, min_distance, threads));
}

}  // namespace glint
