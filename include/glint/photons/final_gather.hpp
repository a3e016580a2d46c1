// glint/photons/final_gather.hpp: the final gather of photon mapping (Jensen 2001, ch. 9;
// Larsen 2004, §4.5: 500 to 2000 rays): indirect radiance at a shading point estimated by rays
// sampled from its BRDF, each returning the radiance that the photon maps give at the
// surface it hits (typically kd / pi times the precomputed irradiance there):
//   L_ind(x, w) ~ (1 / N) sum_j f(w_j) cos(theta_j) / p(w_j) L(hit_j, -w_j).
// The directions are stratified (Jensen 2001, ch. 9): the first m^2 of N rays, m =
// floor(sqrt(N)), take one jittered point in each cell of an m x m grid over the BRDF
// sample's unit square; the rest are independent.
#pragma once

#include <cmath>
#include <concepts>
#include <limits>

#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/tracer/shading.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// (1 / rays) sum of BRDF-sampled rays' f cos / p times radiance(ray, hit), hit null where
/// the ray leaves the scene. queries: RayQueries or any type with closest_hit(ray, hit);
/// uniform(): the next number in [0, 1) of the caller's stream.
template <class Queries, class Uniform, class Radiance, Scalar T>
    requires requires(Queries& q, const Ray<T>& r, StoreHit<T>& h, Uniform& u) {
        { q.closest_hit(r, h) } -> std::convertible_to<bool>;
        { u() } -> std::convertible_to<T>;
    }
Rgb<T> final_gather(Queries& queries, const ShadingPoint<T>& sp, int rays, Uniform& uniform, const Radiance& radiance) {
    if (rays <= 0) return Rgb<T>(T(0));
    const int m = int(std::sqrt(double(rays)));
    Rgb<T> sum(T(0));
    for (int j = 0; j < rays; ++j) {
        const T u0 = T(uniform());
        Vec2<T> u{u0, T(uniform())};
        if (j < m * m) u = Vec2<T>((T(j % m) + u.x) / T(m), (T(j / m) + u.y) / T(m));
        u = glm::min(u, Vec2<T>(T(1) - std::numeric_limits<T>::epsilon()));
        const Vec3<T> wl = sp.brdf->sample_by_albedo(u);
        const T pdf = sp.brdf->sampling_pdf(wl);
        if (!(pdf > T(0)) || wl.z <= T(0)) continue;
        const Rgb<T> w = sp.brdf->f(wl) * (wl.z / pdf);
        if (!(w.max() > T(0))) continue;
        const Ray<T> ray = spawn(sp, sp.frame.to_world(wl));
        StoreHit<T> hit;
        sum += w * (queries.closest_hit(ray, hit) ? radiance(ray, &hit) : radiance(ray, static_cast<const StoreHit<T>*>(nullptr)));
    }
    return sum / T(rays);
}

}  // namespace glint
