// glint/tracer/render.hpp: choosing the path tracer's policies by name, once, at the top.
//
// The command line and the benchmarks name policies as strings; render() checks the scene's
// features once (environment map? point lights?) and instantiates the PathTracer variant with
// exactly those, for the named sampler, roulette and direct-lighting policies. The
// accelerator is the kd-tree with IVM leaves and the compact-subtree layout (trees/).
//
// Names: roulette  classic | spectral | estimate | spectral+estimate
//        direct    brdf | mis | importance | correlated | combined
//        selection dis | w | mis
//        sampler   random | halton
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/intersection/ivm.hpp>
#include <glint/sampling/halton.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/traversal.hpp>

namespace glint {

/// The accelerator render() builds: SAH kd-tree, IVM leaves, compact 15-node subtrees.
using RenderAccel = KdTree<float, Ivm<float>, CompactSubtrees<15>>;

struct RenderOptions {
    RenderSettings settings{};
    std::string roulette = "spectral";
    std::string direct = "mis";
    std::string sampler = "random";
    std::uint64_t seed = 0;
};

inline const std::vector<std::string>& roulette_names() {
    static const std::vector<std::string> v{"classic", "spectral", "estimate", "spectral+estimate"};
    return v;
}
inline const std::vector<std::string>& direct_names() {
    static const std::vector<std::string> v{"brdf", "mis", "importance", "correlated", "combined"};
    return v;
}

inline BrdfSelection parse_selection(const std::string& s) {
    if (s == "dis") return BrdfSelection::decomposition;
    if (s == "w") return BrdfSelection::weighted;
    if (s == "mis") return BrdfSelection::mis;
    throw Error("unknown BRDF selection '" + s + "' (dis, w, mis)");
}

namespace detail {

template <class S, class R, class D>
RenderResult render_with(const Scene<float>& scene, const RenderAccel& accel, const R& roulette,
                         const RenderSettings& settings, const S& sampler) {
    const SceneFeatures f = scene.features();
    auto run = [&]<bool Env, bool Points>() {
        return PathTracer<RenderAccel, S, R, D, Env, Points>(scene, accel, roulette, settings).render(sampler);
    };
    if (f.environment) return f.point_lights ? run.template operator()<true, true>() : run.template operator()<true, false>();
    return f.point_lights ? run.template operator()<false, true>() : run.template operator()<false, false>();
}

template <class S, class R>
RenderResult render_direct(const Scene<float>& scene, const RenderAccel& accel, const R& roulette,
                           RenderSettings settings, const std::string& direct, const S& sampler) {
    if (direct == "brdf") return render_with<S, R, BrdfOnlyDirect>(scene, accel, roulette, settings, sampler);
    if (direct == "mis") return render_with<S, R, MisDirect>(scene, accel, roulette, settings, sampler);
    if (direct == "importance") settings.estimator = DirectEstimator::importance;
    else if (direct == "correlated") settings.estimator = DirectEstimator::correlated;
    else if (direct == "combined") settings.estimator = DirectEstimator::combined;
    else throw Error("unknown direct lighting '" + direct + "' (brdf, mis, importance, correlated, combined)");
    return render_with<S, R, CorrelatedDirect>(scene, accel, roulette, settings, sampler);
}

template <class S>
RenderResult render_roulette(const Scene<float>& scene, const RenderAccel& accel, const RenderOptions& o,
                             const S& sampler) {
    const std::string& r = o.roulette;
    if (r == "classic") return render_direct(scene, accel, ClassicRoulette<float, 3>{}, o.settings, o.direct, sampler);
    if (r == "spectral") return render_direct(scene, accel, SpectralRoulette<float, 3>{}, o.settings, o.direct, sampler);
    if (r == "estimate" || r == "spectral+estimate") {
        Rgb<float> power, albedo;
        float area;
        scene.radiance_estimate_inputs(power, area, albedo);
        const Rgb<float> estimate = global_radiance_estimate(power, area, albedo);
        if (r == "estimate")
            return render_direct(scene, accel,
                                 RadianceEstimateRoulette<float, 3, ClassicRoulette<float, 3>>{{}, estimate},
                                 o.settings, o.direct, sampler);
        return render_direct(scene, accel, RadianceEstimateRoulette<float, 3>{{}, estimate}, o.settings, o.direct,
                             sampler);
    }
    throw Error("unknown roulette '" + r + "' (classic, spectral, estimate, spectral+estimate)");
}

}  // namespace detail

/// Renders `scene` with the accelerator `accel` (built over scene.triangles) and the named
/// policies.
inline RenderResult render(const Scene<float>& scene, const RenderAccel& accel, const RenderOptions& o) {
    if (o.sampler == "random") return detail::render_roulette(scene, accel, o, RandomSampler<float>(o.seed));
    if (o.sampler == "halton")
        return detail::render_roulette(scene, accel, o,
                                       HaltonSampler<float>(o.settings.width, o.settings.height, 256,
                                                            HaltonRandomization::owen, o.seed));
    throw Error("unknown sampler '" + o.sampler + "' (random, halton)");
}

}  // namespace glint
