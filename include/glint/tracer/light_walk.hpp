// glint/tracer/light_walk.hpp: one random walk from a light carrying power through the scene's
// materials, the step shared by the methods that trace light forwards: the VPL method's
// shooting walks (Keller 1997; Szécsi 2009, §1.4) and photon tracing (Jensen 2001, ch. 5).
//
// At a mirror or dielectric the walk follows specular_direction (Fresnel choice for a
// dielectric) under the roulette with the specular albedo; at any other surface it calls the
// visitor with the power that arrived there, then scatters by the material's own BRDF
// (SurfaceBrdf, glint::scatter) under the roulette. The roulette decides on the normalized
// throughput (the power's colour, largest band 1). Random numbers per vertex: specular, two
// (roulette, Fresnel choice); otherwise three (lobe or termination, two for the direction).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>

#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// What a light walk reports at a non-specular hit.
template <Scalar T>
struct LightWalkVertex {
    Vec3<T> x;                    ///< hit point
    Vec3<T> n;                    ///< geometric normal on the side the walk arrived from
    Vec3<T> direction;            ///< unit direction the walk arrived in (towards the surface)
    Rgb<T> power;                 ///< power arriving at x
    const Material<T>* material;  ///< the hit's material (not specular; kd textured): valid during the visit only
    std::uint32_t triangle;       ///< the scene triangle hit
    int depth;                    ///< scattering vertices before this one (first_depth at the first hit)
    bool first;                   ///< no non-specular vertex before this one on the walk
    bool via_specular;            ///< a mirror or dielectric lies between the walk's start and x
};

namespace detail {

/// Ray origin offset off a surface of normal n towards dir, scaled to the coordinates.
template <Scalar T>
Ray<T> light_spawn(const Vec3<T>& x, const Vec3<T>& n, const Vec3<T>& dir) {
    const T m = std::max({std::abs(x.x), std::abs(x.y), std::abs(x.z), T(1)});
    const T eps = m * T(sizeof(T) == 4 ? 2e-5 : 1e-9);
    return Ray<T>{x + (glm::dot(dir, n) >= T(0) ? n : -n) * eps, dir, T(0), infinity<T>};
}

}  // namespace detail

/// Follows one walk from `ray` carrying `power` (the first hit's incoming power), calling
/// visit(const LightWalkVertex<T>&) at each non-specular hit (see the header comment).
/// `first_depth` counts the scattering vertices before the ray (for the roulette).
template <RayAccelerator A, class R, class Visit, Scalar T = typename A::scalar_type>
    requires RoulettePolicy<R, T, 3>
void light_walk(const Scene<T>& s, const A& accel, const R& roulette, Ray<T> ray, const Rgb<T>& power, Pcg32& rng,
                int max_depth, int first_depth, Visit&& visit) {
    const T scale = power.max();
    if (!(scale > T(0)) || !power.is_finite()) return;
    Rgb<T> beta = power / scale;  // colour of the power, max 1: what the roulette sees
    bool first = true, via_specular = false;
    for (int depth = first_depth; depth < max_depth; ++depth) {
        StoreHit<T> hit;
        if (!accel.closest_hit(ray, hit)) return;
        const Material<T> m = s.material_at(hit.id, hit.u, hit.v);
        const Vec3<T> ng = s.normal(hit.id);
        const Vec3<T> n = glm::dot(ng, ray.direction) < T(0) ? ng : -ng;
        const Vec3<T> x = ray.at(hit.t);
        if (m.specular()) {
            const Rgb<T> a = specular_albedo(m);
            const std::array<Rgb<T>, 1> lobes{a};
            const auto sel = select_lobe(roulette, beta, std::span<const Rgb<T>>(lobes), rng.uniform<T>(), depth);
            if (sel.terminated()) return;
            beta *= a / sel.probability[0];
            via_specular = true;
            ray = detail::light_spawn(x, n, specular_direction(m, ray.direction, ng, rng.uniform<T>()));
            continue;
        }
        visit(LightWalkVertex<T>{x, n, safe_normalize(ray.direction), beta * scale, &m, hit.id, depth, first, via_specular});
        first = false;
        const Frame<T> frame = Frame<T>::from_normal(n);
        const SurfaceBrdf<T> brdf(m, frame.to_local(-safe_normalize(ray.direction)));
        const T u_sel = rng.uniform<T>();
        const Vec2<T> u_dir(rng.uniform<T>(), rng.uniform<T>());
        const ScatterSample<T, 3> step = scatter(brdf, roulette, beta, u_sel, u_dir, depth);
        if (step.terminated()) return;
        beta *= step.weight;
        if (!(beta.max() > T(0)) || !beta.is_finite()) return;
        ray = detail::light_spawn(x, n, frame.to_world(step.direction));
    }
}

}  // namespace glint
