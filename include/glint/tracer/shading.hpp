// glint/tracer/shading.hpp: what light transport knows about a surface point, and the rays
// one path sample traces from it.
//
// ShadingPoint is a vertex's position (with its rounding-error bound), geometric normal (for
// ray offsets), shading normal with its local frame, and BRDF; RayQueries<Accel> traces a
// sample's rays through an accelerator and counts them (the count is the sample's result,
// PathSample::rays, so no function takes a counter to update).
// Ray origins are offset past the point's error bound (core/offset.hpp: Pharr, Jakob,
// Humphreys 2023, sections 6.8.5-6.8.6), so that the same scene renders the same image at any
// translation and scale float resolves.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>

#include <glint/core/math.hpp>
#include <glint/core/offset.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/sampling/correlated.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// The per-vertex inputs of a lighting policy.
template <Scalar T>
struct ShadingPoint {
    Vec3<T> x;          ///< Position in world space.
    Vec3<T> err;        ///< Bound on x's rounding error, per axis (for offsetting shadow-ray origins).
    /// Unit geometric normal on the side of the outgoing direction: where rays leaving the
    /// point are offset to (core/offset.hpp).
    Vec3<T> ng;
    /// Unit shading normal on ng's side (Scene::shading_normal; ng where the scene has no
    /// vertex normals): the cosines of lighting and the BRDF's frame.
    Vec3<T> n;
    Frame<T> frame;     ///< Local frame about n (z = n), in which the BRDF is evaluated.
    const SurfaceBrdf<T>* brdf;  ///< The surface's BRDF; not owned.
};

/// Point light pl's f I cos / r^2 at sp, without visibility, into `out`; false (no ray to
/// cast) where it cannot contribute: behind the shading plane or outside the light's cone.
template <Scalar T>
bool point_light_unshadowed(const PointLight<T>& pl, const ShadingPoint<T>& sp, Rgb<T>& out) {
    const Vec3<T> d = pl.position - sp.x;
    const T r2 = glm::dot(d, d);
    const Vec3<T> wi = d / std::sqrt(r2);
    const Vec3<T> wl = sp.frame.to_local(wi);
    const Rgb<T> I = pl.intensity_towards(-wi);
    if (wl.z <= T(0) || I.max() <= T(0)) return false;
    out = I * sp.brdf->f(wl) * (wl.z / r2);
    return true;
}

/// How emission found at the end of a ray is weighted, given the vertex the ray left: whole
/// (camera rays, specular bounces, no light sampling), or, where lights were also sampled
/// there, by the lighting policies' weight for a BRDF sample of density `pdf`; x and n are
/// that vertex's position and normal (a light selector's probabilities depend on them).
template <Scalar T>
struct Arrival {
    bool lights_sampled = false;  ///< Whether lights were sampled at the vertex the ray left; false weighs emission whole.
    T pdf = T(0);                 ///< Solid-angle density of the BRDF sample that made the ray (used only if lights_sampled).
    /// Position of the vertex the ray left, in world space.
    Vec3<T> x{0}, n{0};  ///< Unit normal at the vertex the ray left.
};

/// The hit point interpolated from the triangle's vertices by the hit's barycentrics, and
/// its error bound (core/offset.hpp).
template <Scalar T>
SurfacePoint<T> surface_point(const Scene<T>& scene, const StoreHit<T>& hit) {
    return surface_point(scene.triangles[hit.id], hit.u, hit.v);
}

/// The shading point that a ray of direction d finds at `hit` on a triangle of geometric
/// normal g (Scene::normal), without its BRDF: g turned towards the ray's origin, the shading
/// normal on that side (Scene::shading_normal) and its frame.
template <Scalar T>
[[gnu::always_inline]] inline ShadingPoint<T> shading_point(const Scene<T>& scene, const StoreHit<T>& hit, const Vec3<T>& g, const Vec3<T>& d) {
    const Vec3<T> ng = glm::dot(g, d) < T(0) ? g : -g;
    const Vec3<T> n = scene.shading_normal(hit.id, hit.u, hit.v, ng);
    const SurfacePoint<T> p = surface_point(scene, hit);
    return {p.x, p.err, ng, n, Frame<T>::from_normal(n), nullptr};
}

/// A ray leaving shading point sp in direction dir.
template <Scalar T>
Ray<T> spawn(const ShadingPoint<T>& sp, const Vec3<T>& dir) {
    return Ray<T>{offset_origin(sp.x, sp.err, sp.ng, dir), dir, T(0), infinity<T>};
}

/// What a lighting policy asks of a sample's ray queries: shadow rays to a point of a polygon
/// light, to a point (rounding error, surface normal; 0 for a point light) and along a ray of
/// infinite length.
template <class Q, class T>
concept ShadowQueries = requires(Q& q, const ShadingPoint<T>& sp, const PolygonLight<T, 3>& light, const Vec3<T>& y,
                                 const Ray<T>& ray) {
    { q.visible(sp, light, y) } -> std::convertible_to<bool>;
    { q.visible(sp, y, y, y) } -> std::convertible_to<bool>;
    { q.unoccluded(ray) } -> std::convertible_to<bool>;
};

/// The rays of one path sample through accelerator A (trees/tree.hpp's RayAccelerator, on
/// rays of its scalar_type), counted.
template <RayAccelerator A>
class RayQueries {
public:
    using T = typename A::scalar_type;  ///< Floating-point type of the rays, the accelerator's.
    /// Queries against `accel`, which must outlive this object; the count starts at zero.
    explicit RayQueries(const A& accel) : accel_(accel) {}

    /// Nearest hit of `ray` within its [tmin, tmax] into `hit`; false if the ray hits nothing.
    bool closest_hit(const Ray<T>& ray, StoreHit<T>& hit) {
        ++rays_;
        return accel_.closest_hit(ray, hit);
    }
    /// Whether nothing blocks `ray` (a shadow ray of infinite length, e.g. to the environment).
    bool unoccluded(const Ray<T>& ray) {
        ++rays_;
        return !accel_.any_hit(ray);
    }
    /// Shadow ray from sp to point y (rounding error y_err, on a surface of normal ny; zero
    /// for a point light), both ends offset off their surfaces, stopping just short of y.
    bool visible(const ShadingPoint<T>& sp, const Vec3<T>& y, const Vec3<T>& y_err, const Vec3<T>& ny) {
        const Vec3<T> xo = offset_origin(sp.x, sp.err, sp.ng, y - sp.x);
        const Vec3<T> yo = offset_origin(y, y_err, ny, xo - y);
        return unoccluded(Ray<T>{xo, yo - xo, T(0), T(1) - T(sizeof(T) == 4 ? 1e-4 : 1e-9)});
    }
    /// Shadow ray from sp to point y of a polygon light.
    bool visible(const ShadingPoint<T>& sp, const PolygonLight<T, 3>& light, const Vec3<T>& y) {
        // A point of the light polygon is a convex combination of its vertices.
        T m = 0;
        for (const auto& v : light.sampler().vertices()) m = std::max({m, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
        return visible(sp, y, coordinate_error(m), light.sampler().normal());
    }
    /// Number of rays cast through this object so far (closest-hit and shadow rays).
    std::uint64_t rays() const { return rays_; }

private:
    const A& accel_;
    std::uint64_t rays_ = 0;
};

}  // namespace glint
