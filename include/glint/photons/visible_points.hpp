// glint/photons/visible_points.hpp: the points where photon-mapping integrators estimate
// radiance: a camera ray followed through mirrors and dielectrics (the Fresnel choice drawn
// from the pixel sample's stream) to its first diffuse or glossy vertex, which keeps the
// path's throughput, its outgoing direction and its material (Hachisuka and Jensen 2009's
// visible points; the first diffuse surface of Jensen 2001, ch. 9's eye ray). Emission met on
// the way (at the camera vertex, after specular bounces and at the point itself) is the
// path's own radiance, counted whole.
//
// direct_at() estimates direct light at a visible point with a lighting policy of
// tracer/lighting.hpp (a DirectLighting: its light samples) plus one BRDF-sampled ray whose
// emission counts with the policy's weight (for MisDirect, the balance heuristic; for
// BrdfOnlyDirect, whole). Environment maps are not handled here (photons do not come from them).
//
// VisiblePointIntegrator runs the camera pass under tracer/renderer.hpp's Renderer (one
// sample per pixel, the sampler's per-pixel stream) and leaves every pixel's point and the
// radiance the camera pass estimated (emission met, direct light) on a VisiblePointFilm.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glint/core/image.hpp>
#include <glint/core/math.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// A camera path's first diffuse or glossy vertex (valid = false where the path escaped,
/// met only specular surfaces up to the cap, or carries no throughput).
template <Scalar T>
struct VisiblePoint {
    /// World-space position of the vertex.
    Vec3<T> x{0}, err{0};  ///< Rounding-error bound of x, per axis (for offsetting rays off it).
    Vec3<T> n{0};   ///< Unit geometric normal on the side the path arrived from.
    Vec3<T> wo{0};  ///< Unit direction back along the path.
    Rgb<T> beta{T(0)};  ///< The path's throughput through its specular vertices.
    std::uint32_t material = 0;  ///< Index of the vertex's material in Scene::materials.
    std::uint32_t triangle = 0;  ///< Index of the triangle the vertex lies on in Scene::triangles.
    bool valid = false;          ///< A point was found (false: the other fields are meaningless).

    /// The point's BRDF in its own frame (frame must be this point's Frame::from_normal(n)).
    SurfaceBrdf<T> brdf(const Scene<T>& s, const Frame<T>& frame) const {
        return SurfaceBrdf<T>(s.materials[material], frame.to_local(wo));
    }
    /// beta f(wo, wi) for light arriving from world direction wi (unit, leaving the surface);
    /// zero from behind the surface.
    Rgb<T> weight(const Scene<T>& s, const Vec3<T>& wi) const {
        if (glm::dot(wi, n) <= T(0)) return Rgb<T>(T(0));
        const Frame<T> frame = Frame<T>::from_normal(n);
        return beta * brdf(s, frame).f(frame.to_local(wi));
    }
};

/// The camera ray's walk to its visible point: up to max_specular mirror or dielectric
/// vertices. Returns the emission seen on the way (weighted by the throughput).
template <RayAccelerator A, Scalar T, class U>
Rgb<T> find_visible_point(const Scene<T>& s, RayQueries<A>& rays, Ray<T> ray, int max_specular, U&& uniform,
                          VisiblePoint<T>& vp) {
    vp = VisiblePoint<T>{};
    Rgb<T> beta(T(1)), L(T(0));
    for (int depth = 0; depth <= max_specular; ++depth) {
        StoreHit<T> hit;
        if (!rays.closest_hit(ray, hit)) break;
        const Material<T>& m = s.materials[s.material_of[hit.id]];
        const Vec3<T> ng = s.normal(hit.id);
        const bool front = glm::dot(ng, ray.direction) < T(0);
        const Vec3<T> n = front ? ng : -ng;
        const SurfacePoint<T> p = surface_point(s, hit);
        if (front && m.emissive()) L += beta * m.emission;
        if (!m.specular()) {
            vp = VisiblePoint<T>{p.x, p.err, n, -safe_normalize(ray.direction), beta, s.material_of[hit.id], std::uint32_t(hit.id),
                                 beta.max() > T(0)};
            break;
        }
        const T u = m.kind == MaterialKind::dielectric ? uniform() : T(0);
        const Vec3<T> wi = specular_direction(m, ray.direction, ng, u);
        beta *= specular_albedo(m);
        ray = Ray<T>{offset_origin(p.x, p.err, n, wi), wi, T(0), infinity<T>};
    }
    return L;
}

/// Direct light leaving vp towards the camera, weighted by vp's throughput: the lighting
/// policy's light samples plus one BRDF sample's emission, weighted as the policy says.
template <class D, RayAccelerator A, class S, Scalar T>
    requires DirectLighting<D, T, RayQueries<A>, S>
Rgb<T> direct_at(const Scene<T>& s, RayQueries<A>& rays, const D& direct, const VisiblePoint<T>& vp, S& sampler) {
    const Frame<T> frame = Frame<T>::from_normal(vp.n);
    const SurfaceBrdf<T> brdf = vp.brdf(s, frame);
    const ShadingPoint<T> sp{vp.x, vp.err, vp.n, vp.n, frame, &brdf};
    Rgb<T> L = direct.estimate(sp, sampler, rays, static_cast<typename D::vertex_record*>(nullptr));
    const Vec3<T> wl = brdf.sample_by_albedo(sampler.get_2d());
    const T pdf = brdf.sampling_pdf(wl);
    if (!(pdf > T(0)) || wl.z <= T(0)) return L * vp.beta;
    const Ray<T> ray = spawn(sp, frame.to_world(wl));
    StoreHit<T> hit;
    if (rays.closest_hit(ray, hit)) {
        const Material<T>& m = s.materials[s.material_of[hit.id]];
        if (m.emissive() && glm::dot(s.normal(hit.id), ray.direction) < T(0))
            L += m.emission * brdf.f(wl) * (wl.z / pdf) * direct.emission_weight(Arrival<T>{true, pdf, sp.x, sp.n}, ray, hit);
    }
    return L * vp.beta;
}

/// A film of visible points and the radiance each pixel's camera pass estimated, row by row.
template <Scalar T>
struct VisiblePointFilm {
    /// Image width in pixels.
    int width = 0, height = 0;  ///< Image height in pixels.
    std::vector<VisiblePoint<T>> points;  ///< Each pixel's kept visible point, row by row.
    std::vector<Rgb<T>> radiance;  ///< Emission met and direct light at the point: the mean over the pixel's samples.

    /// Sizes the film to w x h pixels, every point invalid and every radiance 0.
    void resize(int w, int h) {
        width = w;
        height = h;
        points.assign(std::size_t(w) * std::size_t(h), VisiblePoint<T>{});
        radiance.assign(points.size(), Rgb<T>(T(0)));
    }
    /// Stores pixel (x, y)'s mean radiance; the Renderer calls it (the second value, the
    /// variance of the mean, is not kept).
    void set_pixel(int x, int y, const Rgb<T>& mean, const Rgb<T>&) {
        radiance[std::size_t(y) * std::size_t(width) + std::size_t(x)] = mean;
    }
};

/// The camera pass: per pixel sample, the emission met plus the direct light at its visible
/// point by lighting policy D (the film's radiance: their mean over the pixel's samples); the
/// pixel keeps the visible point of its sample number `keep` (0-based, in this render's
/// order; the last one where the pixel has fewer samples). Which one is kept matters to
/// quasi-random samplers: passes that always kept sample c - 1 of c would keep the Halton
/// points i = c - 1 mod c, whose leading digits are fixed (a c-th of the pixel in x for c a
/// power of 2); a caller that cycles `keep` over the passes keeps a stratified sequence.
template <RayAccelerator A, class D, Scalar T = typename A::scalar_type>
class VisiblePointIntegrator {
public:
    using scalar_type = T;  ///< The scene's scalar type.
    /// A pixel's kept visible point and the samples it has taken so far.
    struct pixel_state {
        VisiblePoint<T> point;  ///< The visible point kept (sample `keep`'s, or the last one's).
        int samples = 0;        ///< Samples taken so far.
    };

    /// The camera pass over s through `accel` with direct-lighting policy `direct`, following
    /// up to max_specular specular vertices, keeping sample `keep`'s visible point; s, accel
    /// and direct are kept by reference and must outlive it.
    VisiblePointIntegrator(const Scene<T>& s, const A& accel, const D& direct, int max_specular, int keep = 0)
        : scene_(s), accel_(accel), direct_(direct), max_specular_(max_specular), keep_(keep) {
        s.require_untextured("glint::VisiblePointIntegrator");
    }

    /// One pixel sample: emission met plus direct light at its visible point, which `state`
    /// keeps up to sample `keep`; with the rays traced.
    template <class S>
        requires Sampler<S, T> && DirectLighting<D, T, RayQueries<A>, S>
    PathSample<T> radiance(const Ray<T>& ray, S& sampler, pixel_state& state) const {
        RayQueries<A> rays(accel_);
        VisiblePoint<T> vp;
        Rgb<T> L = find_visible_point(scene_, rays, ray, max_specular_, [&sampler] { return sampler.get_1d(); }, vp);
        if (vp.valid) L += direct_at(scene_, rays, direct_, vp, sampler);
        if (state.samples++ <= keep_) state.point = vp;
        return {L, rays.rays(), false};
    }

    /// Copies every pixel's kept visible point onto the film.
    void finish(VisiblePointFilm<T>& film, std::span<const pixel_state> states) const {
        film.points.resize(states.size());
        for (std::size_t i = 0; i < states.size(); ++i) film.points[i] = states[i].point;
    }

private:
    const Scene<T>& scene_;
    const A& accel_;
    const D& direct_;
    int max_specular_;
    int keep_;
};

/// The visible points of one pass: the camera rays of `image` (image.spp per pixel) with the
/// streams of `sampler`, direct light by `direct`, each pixel keeping sample `keep`'s point.
template <RayAccelerator A, class D, class S, Scalar T = typename A::scalar_type>
    requires Sampler<S, T> && DirectLighting<D, T, RayQueries<A>, S>
RenderStats visible_points(const Scene<T>& s, const A& accel, const D& direct, const RenderSettings& image,
                           int max_specular, const S& sampler, VisiblePointFilm<T>& film, int keep = 0) {
    return render_image(s, image, VisiblePointIntegrator<A, D, T>(s, accel, direct, max_specular, keep), sampler, film);
}

}  // namespace glint
