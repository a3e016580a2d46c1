// glint/tracer/path_tracer.hpp: the bundled reference path tracer, an integrator composed of
// policies.
//
// Szécsi 2009, §1.3: the rendering equation L = Le + T L is estimated by random walks; at
// every diffuse or glossy vertex the direct illumination is estimated by a direct-lighting
// policy (next-event estimation: area and point lights, as the policy chooses), the
// environment by an environment-lighting policy, and the walk continues or stops by the Russian roulette and
// BRDF selection of PathTracerSettings (§2.1-2.3 through glint::scatter). Types, where they
// pay in the hot loop:
//   Accel    a RayAccelerator (trees/tree.hpp): closest_hit(ray, StoreHit&) and any_hit(ray)
//            (MeshBvh, KdTree, Bih, BruteForce); its scalar_type is the tracer's;
//   S        glint::Sampler (RandomSampler, HaltonSampler);
//   D        DirectLighting (tracer/lighting.hpp: BrdfOnlyDirect, MisDirect; CorrelatedDirect
//            in tracer/correlated_direct.hpp; or a user's own);
//   E        EnvironmentLighting (MisEnvironment, the default, which does nothing in a scene
//            without a map; CorrelatedEnvironment in tracer/correlated_environment.hpp).
// Values, a predictable branch per vertex: the roulette rule, the BRDF selection, the scene's
// features (the environment: checked once, when the tracer is built). Specular (mirror, dielectric) vertices are followed
// deterministically (Fresnel choice for dielectrics) and count emission on the next hit, as
// camera rays do.
//
// The tracer is an Integrator (tracer/renderer.hpp): radiance(ray, sampler, pixel_state) gives
// one sample's radiance and rays, finish(film, states) lets the direct-lighting policy finish
// its per-pixel statistics. Tiles, threads, progress and the film are the Renderer's.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <span>
#include <vector>

#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/path_tracer_settings.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// The reference path tracer (Szécsi 2009, §1.3): an Integrator that estimates the radiance
/// along camera rays by random walks with next-event estimation by direct-lighting policy D,
/// environment light by policy E and Russian roulette and BRDF selection by PathTracerSettings.
/// It keeps references to the scene and the accelerator, which must outlive it; radiance() is
/// const and may be called from many threads at once, each with its own sampler.
template <RayAccelerator Accel, class S, class D, class E = MisEnvironment<typename Accel::scalar_type>>
    requires Sampler<S, typename Accel::scalar_type> &&
             DirectLighting<D, typename Accel::scalar_type, RayQueries<Accel>, S> &&
             EnvironmentLighting<E, typename Accel::scalar_type, RayQueries<Accel>, S>
class PathTracer {
public:
    /// The floating-point type of rays, radiance and the scene (the accelerator's).
    using scalar_type = typename Accel::scalar_type;
    /// Short name for scalar_type.
    using T = scalar_type;
    /// Per-pixel statistics of the direct-lighting policy D (an empty struct when it keeps none).
    using pixel_state = typename D::pixel_state;
    /// The counting ray-query wrapper over Accel that the walk traces through (one per radiance() call).
    using Queries = RayQueries<Accel>;
    /// Russian roulette, BRDF selection and depth cap of the walk.
    using Settings = PathTracerSettings<T>;

    /// A tracer of `scene` through `accel` (built over the same scene's triangles) with the given
    /// lighting policies, which are copied. Throws glint::Error if scene.validate() fails.
    PathTracer(const Scene<T>& scene, const Accel& accel, const D& direct, const E& environment, const Settings& settings)
        : scene_(scene), accel_(accel), direct_(direct), env_(environment), settings_(settings), features_(scene.features()) {
        scene.validate();
    }
    /// With the lighting policies built from the scene and settings.
    PathTracer(const Scene<T>& scene, const Accel& accel, const Settings& settings = {})
        requires std::constructible_from<D, const Scene<T>&, const Settings&> && std::constructible_from<E, const Scene<T>&>
        : PathTracer(scene, accel, D(scene, settings), E(scene), settings) {}

    /// Radiance along a camera ray; the direct-lighting policy records the sample in `state`.
    PathSample<T> radiance(const Ray<T>& ray, S& sampler, pixel_state& state) const {
        return camera_sample(ray, nullptr, sampler, state);
    }
    /// The closest hits of camera rays as one stream (the accelerator's packets where it has
    /// them, trees/tree.hpp's closest_hits()), for radiance(ray, first, ...) to continue from;
    /// `hits` must start empty (StoreHit{}). The Renderer traces a tile's rays this way.
    void first_hits(std::span<const Ray<T>> rays, std::span<StoreHit<T>> hits) const { closest_hits(accel_, rays, hits); }
    /// The same sample as radiance(ray, sampler, state), from the camera ray's closest hit
    /// `first` that first_hits() found (or not: first.found() false), counted as one ray.
    PathSample<T> radiance(const Ray<T>& ray, const StoreHit<T>& first, S& sampler, pixel_state& state) const {
        return camera_sample(ray, &first, sampler, state);
    }
    /// Radiance along a camera ray with nothing kept for the pixel (for tests).
    PathSample<T> radiance(const Ray<T>& ray, S& sampler) const {
        pixel_state state;
        return radiance(ray, sampler, state);
    }
    /// The direct-lighting policy's film values, on any film it can finish on.
    template <class F>
        requires requires(const D& d, F& film, std::span<const pixel_state> states) { d.finish(film, states); }
    void finish(F& film, std::span<const pixel_state> states) const {
        direct_.finish(film, states);
    }

    /// The direct-lighting policy the tracer owns.
    const D& direct() const { return direct_; }
    /// The settings the tracer was built with.
    const Settings& settings() const { return settings_; }

    /// Pilot observations for Szécsi 2009, §2.3's radiance estimate: at the first diffuse
    /// vertex of `n` camera paths through the pixels of `image`, the albedo a and the
    /// one-sample reflected radiance X = (w/p) L_in (L_in traced by this tracer, so unbiased),
    /// `repeats` of them per vertex (consecutive; more than 1 for estimate_goodness_floor). X
    /// is what the roulette decides about, what a terminated walk loses: emission met by the
    /// continued ray counts with the direct-lighting policy's weight, as in the walk. A
    /// direction the BRDF cannot sample gives X = 0, as in the walk.
    std::vector<RoulettePilotSample<T, 3>> pilot_samples(const RenderSettings& image, const S& prototype, int n,
                                                         int repeats = 1) const {
        S sampler = prototype;
        std::vector<RoulettePilotSample<T, 3>> out;
        repeats = std::max(repeats, 1);
        out.reserve(std::size_t(std::max(n, 0)) * std::size_t(repeats));
        const PixelCamera<T> camera(scene_.camera, image);
        const std::uint64_t pixels = std::uint64_t(image.width) * std::uint64_t(image.height);
        for (int i = 0; i < n; ++i) {
            // Pixels spread over the whole image (an odd multiplier not divisible by 3 permutes
            // the indices of a w x h image with w h = 2^k 3^j; any other size is still covered
            // widely), not the first rows: the fit must see every part of the scene.
            const std::uint64_t k = (std::uint64_t(i) * 0x9E3779B1u) % pixels;
            const int x = int(k % std::uint64_t(image.width)), y = int(k / std::uint64_t(image.width));
            pilot_vertex(camera.ray(x, y, std::uint64_t(0x9000000 + i), sampler), sampler, repeats, out);
        }
        return out;
    }

private:
    /// A camera ray's sample; its closest hit is `first` when the caller traced it (else null).
    PathSample<T> camera_sample(const Ray<T>& ray, const StoreHit<T>* first, S& sampler, pixel_state& state) const {
        Queries queries(accel_);
        typename D::vertex_record rec;
        PathSample<T> out = walk(ray, sampler, queries, Arrival<T>{}, &rec, first);
        direct_.record(state, rec, out.L);
        out.rays = queries.rays() + (first ? 1 : 0);
        return out;
    }

    /// The pilot observations at the vertex a camera ray finds, if it is diffuse or glossy.
    void pilot_vertex(const Ray<T>& ray, S& sampler, int repeats, std::vector<RoulettePilotSample<T, 3>>& out) const {
        Queries queries(accel_);
        StoreHit<T> hit;
        if (!queries.closest_hit(ray, hit)) return;
        const Material<T> m = scene_.material_at(hit.id, hit.u, hit.v);
        if (m.specular()) return;
        ShadingPoint<T> sp = shading_point(scene_, hit, scene_.normal(hit.id), ray.direction);
        const Frame<T>& frame = sp.frame;
        const SurfaceBrdf<T> brdf(m, frame.to_local(-ray.direction));
        sp.brdf = &brdf;
        for (int j = 0; j < repeats; ++j) {
            const Vec3<T> wi = brdf.sample_by_albedo(sampler.get_2d());
            const T pdf = brdf.sampling_pdf(wi);
            Rgb<T> X(T(0));
            if (pdf > T(0) && wi.z > T(0))
                X = brdf.f(wi) * (wi.z / pdf) * walk(spawn(sp, frame.to_world(wi)), sampler, queries, Arrival<T>{true, pdf, sp.x, sp.n}, nullptr).L;
            out.push_back({m.kd + m.ks, X});
        }
    }

    /// The walk from `ray`, which left a vertex as `from` says; `rec`: the primary vertex's
    /// record for the direct-lighting policy (null after the camera ray); `first`: `ray`'s
    /// closest hit when the caller traced it (else null).
    PathSample<T> walk(Ray<T> ray, S& sampler, Queries& queries, Arrival<T> from, typename D::vertex_record* rec,
                       const StoreHit<T>* first = nullptr) const {
        PathSample<T> out;
        Rgb<T> F(T(1));
        for (int depth = 0;; ++depth) {
            if (depth == settings_.max_depth) {
                out.capped = true;
                break;
            }
            StoreHit<T> hit;
            if (first ? !(hit = *first).found() : !queries.closest_hit(ray, hit)) {
                if (features_.environment) out.L += F * env_.escaped(ray.direction, from);
                break;
            }
            first = nullptr;
            const Material<T> m = scene_.material_at(hit.id, hit.u, hit.v);
            const Vec3<T> g = scene_.normal(hit.id);
            const bool front = glm::dot(g, ray.direction) < T(0);
            const ShadingPoint<T> sp = shading_point(scene_, hit, g, ray.direction);
            if (front && m.emissive()) out.L += F * m.emission * direct_.emission_weight(from, ray, hit);
            if (m.specular()) {  // about the shading normal, oriented as g
                if (!specular_step(m, sp, front ? sp.n : -sp.n, depth, sampler, ray, F, out.L)) break;
                from = Arrival<T>{};
                continue;
            }
            if (!surface_step(m, sp, depth, sampler, queries, depth == 0 ? rec : nullptr, ray, F, out.L, from)) break;
        }
        return out;
    }

    /// A diffuse or glossy vertex: lighting policies, then the roulette, lobe
    /// choice and direction (Szécsi 2009, §2.1). Updates ray, F, L and from; false when the
    /// walk stops.
    bool surface_step(const Material<T>& m, ShadingPoint<T> sp, int depth, S& sampler, Queries& queries,
                      typename D::vertex_record* rec, Ray<T>& ray, Rgb<T>& F, Rgb<T>& L, Arrival<T>& from) const {
        const SurfaceBrdf<T> brdf(m, sp.frame.to_local(-ray.direction));
        sp.brdf = &brdf;
        L += F * direct_.estimate(sp, sampler, queries, rec);
        if (features_.environment) L += F * env_.estimate(sp, sampler, queries);
        return scatter_step(brdf, sp, depth, sampler, ray, F, L, from);
    }

    /// The roulette, lobe choice and direction at a diffuse or glossy vertex; everything it
    /// calls is inlined into it (the per-vertex run-time choices cost least there).
    [[gnu::flatten]] bool scatter_step(const SurfaceBrdf<T>& brdf, const ShadingPoint<T>& sp, int depth, S& sampler,
                                       Ray<T>& ray, Rgb<T>& F, Rgb<T>& L, Arrival<T>& from) const {
        const T u_select = sampler.get_1d();
        const Vec2<T> u_dir = sampler.get_2d();
        const ScatterSample<T, 3> s = scatter(brdf, settings_.roulette, F, u_select, u_dir, depth, settings_.selection);
        L += F * s.offset;
        if (s.terminated()) return false;
        F *= s.weight;
        if (F.max() <= T(0) || !F.is_finite()) return false;  // nothing more can contribute
        ray = spawn(sp, sp.frame.to_world(s.direction));
        from = Arrival<T>{true, brdf.sampling_pdf(s.direction), sp.x, sp.n};
        return true;
    }

    /// A mirror or dielectric vertex: the deterministic direction (Fresnel choice for
    /// dielectrics), then the roulette on the one lobe. Updates ray, F and L (the roulette's
    /// offset); false when the walk stops.
    bool specular_step(const Material<T>& m, const ShadingPoint<T>& sp, const Vec3<T>& n, int depth, S& sampler,
                       Ray<T>& ray, Rgb<T>& F, Rgb<T>& L) const {
        const T u = m.kind == MaterialKind::dielectric ? sampler.get_1d() : T(0);  // only a dielectric chooses
        const Vec3<T> wi = specular_direction(m, ray.direction, n, u);
        const std::array<Rgb<T>, 1> lobes{specular_albedo(m)};
        const auto sel = select_lobe(settings_.roulette, F, std::span<const Rgb<T>>(lobes), sampler.get_1d(), depth);
        L += F * sel.offset;
        if (sel.terminated()) return false;
        F *= lobes[0] / sel.probability[0];
        ray = spawn(sp, wi);
        return true;
    }

    const Scene<T>& scene_;
    const Accel& accel_;
    D direct_;
    E env_;
    Settings settings_;
    SceneFeatures features_;  // checked once: a scene without a map skips its code
};

}  // namespace glint
