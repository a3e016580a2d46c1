// glint/photons/photon_integrator.hpp: photon mapping's rendering pass (Jensen 2001, ch. 9; Larsen
// 2004, §4) as an integrator of tracer/renderer.hpp. A camera ray is followed through mirrors
// and dielectrics to its visible point (photons/visible_points.hpp), where the radiance is
// split into
//   direct     a lighting policy of tracer/lighting.hpp (glint-render: MisDirect, light
//              samples and a BRDF sample by the balance heuristic; direct_at);
//   caustics   the caustic map's radiance estimate (L S+ D paths; photons/radiance_estimate.hpp,
//              k nearest within the maximum radius, Jensen's cone filter);
//   indirect   a final gather (photons/final_gather.hpp): BRDF-sampled rays, each followed
//              through specular surfaces to a diffuse one, where the global map's precomputed
//              irradiance E gives kd / pi E (Christensen 1999). Emission a gather ray meets is
//              not counted: direct light and caustics already hold it.
// The global map holds every stored photon of its tracing, direct hits and caustic photons
// included, so that a gather ray sees all the light at its hit. Glossy surfaces at a gather
// ray's hit count only their diffuse lobe (kd / pi E).
//
// PhotonMaps builds the maps (tracing, balancing, precomputing irradiance) for a seed;
// PhotonMapIntegrator renders with them, each rendering thread keeping its kNN scratch
// (thread_state). render_photon_map is one image; with a time budget, glint-render runs passes
// of new maps (a seed each) and averages them (tracer/progressive.hpp).
#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/photons/final_gather.hpp>
#include <glint/photons/photon_map.hpp>
#include <glint/photons/photon_tracing.hpp>
#include <glint/photons/radiance_estimate.hpp>
#include <glint/photons/visible_points.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

namespace detail {
/// An RGB value in another scalar type (the photon maps keep floats).
template <Scalar To, Scalar From>
Rgb<To> rgb_as(const Rgb<From>& c) {
    return Rgb<To>(To(c[0]), To(c[1]), To(c[2]));
}
}  // namespace detail

/// Photon mapping's knobs: photon counts, the estimate's kNN and radius, the final gather.
struct PhotonMapSettings {
    std::size_t photons = 100000;          ///< Emitted for the global map; > 0.
    std::size_t caustic_photons = 400000;  ///< Emitted for the caustic map (its caustic photons kept); > 0.
    std::size_t knn = 50;                  ///< Photons per estimate; > 0.
    float radius = 0.05f;                  ///< Largest search radius (scene units); > 0.
    int gather_rays = 64;                  ///< Final gather rays per pixel sample; >= 0.
    int max_specular = 32;                 ///< Camera and gather paths: most specular vertices followed; >= 0.
    std::uint64_t seed = 0;                ///< Seeds the two tracings (2 seed + 1, 2 seed + 2) and the render.
    int threads = 0;                       ///< Threads for tracing and precomputation (0: hardware concurrency).

    /// Throws Error for a zero count or knn, a radius that is not positive, or negative
    /// gather rays or specular depth.
    void validate() const {
        if (photons == 0 || caustic_photons == 0) throw Error("photon map: photon counts must be positive");
        if (knn == 0) throw Error("photon map: knn must be positive");
        if (!(radius > 0.0f)) throw Error("photon map: radius must be positive, got " + std::to_string(radius));
        if (gather_rays < 0 || max_specular < 0) throw Error("photon map: gather rays and specular depth must be >= 0");
    }
    /// The radiance estimate these settings give: knn within radius, Jensen's cone filter (k = 1).
    RadianceEstimateSettings estimate() const { return {knn, radius, PhotonFilter::cone, 1.0f}; }
};

/// The global map with its precomputed irradiance, and the caustic map.
struct PhotonMaps {
    /// The global map (every stored photon of its tracing, caustic ones included).
    PhotonMap global, caustic;  ///< The caustic map (L S+ D photons of its own tracing).
    PrecomputedIrradiance irradiance;  ///< Irradiance precomputed on the global map (Christensen 1999).
    std::size_t emitted = 0;           ///< Photons emitted by both tracings together.

    /// Traces, balances and precomputes the maps of scene s through `accel` (over its
    /// triangles) with st's counts and seed; throws Error for invalid settings or a scene with
    /// no light that emits.
    template <RayAccelerator A, Scalar T = typename A::scalar_type>
    PhotonMaps(const Scene<T>& s, const A& accel, const PhotonMapSettings& st) {
        st.validate();
        PhotonSettings ps;
        ps.photons = st.photons;
        ps.seed = st.seed * 2 + 1;
        ps.threads = st.threads;
        PhotonSet g = trace_photons(s, accel, ps);
        g.global.insert(g.global.end(), g.caustic.begin(), g.caustic.end());
        global = PhotonMap(std::move(g.global));
        irradiance = PrecomputedIrradiance(global, st.estimate(), st.threads);
        ps.photons = st.caustic_photons;
        ps.seed = st.seed * 2 + 2;
        PhotonSet c = trace_photons(s, accel, ps);
        caustic = PhotonMap(std::move(c.caustic));
        emitted = g.emitted + c.emitted;
    }
};

/// Photon mapping's rendering pass as an integrator of tracer/renderer.hpp: direct light by
/// policy D, caustics from the caustic map, indirect light by final gather on the global map's
/// precomputed irradiance. const and thread-safe; each thread keeps its own thread_state.
template <RayAccelerator A, class D, Scalar T = typename A::scalar_type>
class PhotonMapIntegrator {
public:
    using scalar_type = T;  ///< The scene's scalar type.
    using thread_state = std::vector<PhotonNeighbour>;  ///< A rendering thread's kNN scratch.
    struct pixel_state {};  ///< Empty: no per-pixel state.

    /// `maps` must outlive the integrator.
    PhotonMapIntegrator(const Scene<T>& s, const A& accel, const D& direct, const PhotonMaps& maps,
                        const PhotonMapSettings& st)
        : scene_(s), accel_(accel), direct_(direct), maps_(maps), st_(st), estimate_(st.estimate()) {
        st.validate();
        s.require_untextured("glint::PhotonMapIntegrator");
    }

    /// A fresh, empty kNN scratch for one rendering thread.
    thread_state make_thread_state() const { return {}; }

    /// Radiance along camera ray `ray`: emission seen through specular surfaces, then at the
    /// visible point direct light, caustics and the final gather; with the rays traced.
    template <class S>
        requires Sampler<S, T> && DirectLighting<D, T, RayQueries<A>, S>
    PathSample<T> radiance(const Ray<T>& ray, S& sampler, pixel_state&, thread_state& scratch) const {
        RayQueries<A> rays(accel_);
        auto uniform = [&sampler] { return sampler.get_1d(); };
        VisiblePoint<T> vp;
        PathSample<T> out;
        out.L = find_visible_point(scene_, rays, ray, st_.max_specular, uniform, vp);
        if (vp.valid) {
            out.L += direct_at(scene_, rays, direct_, vp, sampler);
            const Frame<T> frame = Frame<T>::from_normal(vp.n);
            const SurfaceBrdf<T> brdf = vp.brdf(scene_, frame);
            const ShadingPoint<T> sp{vp.x, vp.err, vp.n, vp.n, frame, &brdf};
            out.L += vp.beta * caustics(sp, scratch);
            out.L += vp.beta * final_gather(rays, sp, st_.gather_rays, uniform, [&](const Ray<T>& r, const StoreHit<T>* hit) {
                return hit ? gathered(rays, r, *hit, uniform, scratch) : Rgb<T>(T(0));
            });
        }
        out.rays = rays.rays();
        return out;
    }

    /// Does nothing: photon mapping adds no film layers.
    void finish(Film&, std::span<const pixel_state>) const {}

private:
    /// The caustic map's estimate at sp.
    Rgb<T> caustics(const ShadingPoint<T>& sp, thread_state& scratch) const {
        const auto f = [&](const Vec3<float>& wp) { return detail::rgb_as<float>(sp.brdf->f(sp.frame.to_local(Vec3<T>(wp)))); };
        return detail::rgb_as<T>(radiance_estimate(maps_.caustic, Vec3<float>(sp.x), Vec3<float>(sp.n), f, estimate_, scratch));
    }

    /// Radiance a gather ray brings from its hit: through specular surfaces to a diffuse one,
    /// then kd / pi times the precomputed irradiance there (no emission).
    template <class U>
    Rgb<T> gathered(RayQueries<A>& rays, const Ray<T>& r, const StoreHit<T>& hit, U& uniform, thread_state& scratch) const {
        const Material<T>& m = scene_.materials[scene_.material_of[hit.id]];
        VisiblePoint<T> vp;
        if (!m.specular()) {
            const Vec3<T> ng = scene_.normal(hit.id);
            const SurfacePoint<T> p = surface_point(scene_, hit);
            vp = VisiblePoint<T>{p.x, p.err, glm::dot(ng, r.direction) < T(0) ? ng : -ng, -r.direction, Rgb<T>(T(1)),
                                 scene_.material_of[hit.id], std::uint32_t(hit.id), true};
        } else {
            find_visible_point(scene_, rays, r, st_.max_specular, uniform, vp);  // re-finds hit: simple, rare
            if (!vp.valid) return Rgb<T>(T(0));
        }
        const Rgb<float> E = maps_.irradiance.lookup(maps_.global, Vec3<float>(vp.x), Vec3<float>(vp.n), st_.radius, scratch);
        return vp.beta * scene_.materials[vp.material].kd * detail::rgb_as<T>(E) * (T(1) / pi<T>);
    }

    const Scene<T>& scene_;
    const A& accel_;
    D direct_;
    const PhotonMaps& maps_;
    PhotonMapSettings st_;
    RadianceEstimateSettings estimate_;
};

/// Photon mapping of `s`: the maps of st.seed, then the Renderer with `image`'s settings
/// (streams from st.seed); seconds include building the maps.
template <RayAccelerator A, class D, Scalar T = typename A::scalar_type>
    requires DirectLighting<D, T, RayQueries<A>, RandomSampler<T>>
RenderResult render_photon_map(const Scene<T>& s, const A& accel, const D& direct, const RenderSettings& image,
                               const PhotonMapSettings& st) {
    const auto start = std::chrono::steady_clock::now();
    const PhotonMaps maps(s, accel, st);
    RenderResult r = render_image(s, image, PhotonMapIntegrator<A, D, T>(s, accel, direct, maps, st),
                                  RandomSampler<T>(st.seed));
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
}

}  // namespace glint
