// glint/tracer/render.hpp: choosing the path tracer's policies by name, once, at the top.
//
// The command line and the benchmarks name policies as strings; render() checks the scene's
// features once (environment map? point lights?) and instantiates the PathTracer variant with
// exactly those, for the named sampler, roulette and direct-lighting policies. The
// accelerator is the 8-wide BVH with Moller-Trumbore leaves (trees/mesh_bvh.hpp).
//
// Names: roulette  classic | spectral | estimate | spectral+estimate (000's rules, from the
//                  first vertex); throughput | throughput+spectral | throughput+estimate |
//                  throughput+spectral+estimate (the field's throughput rule from
//                  rr_depth, with 000's spectral norm and radiance estimate on top); none
//                  (no roulette, throughput cut-off)
//        direct    brdf | mis | importance | correlated | combined
//        selection dis | w | mis
//        sampler   random | halton (= halton-perm) | halton-owen | halton-cp
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/sampling/halton.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/trees/traversal.hpp>

namespace glint {

/// The accelerator render() builds: the 8-wide BVH with Moller-Trumbore leaves, glint's
/// fastest tree (docs/trees.md, "Wide BVH").
using RenderAccel = MeshBvh<MollerTrumbore<float>, 8>;

struct RenderOptions {
    RenderSettings settings{};
    /// The default is the field's throughput rule: bench_convergence finds it as efficient
    /// as any roulette on the Cornell scenes (docs/tracer.md); the radiance estimate on top
    /// of it is within the noise there and can make pixels negative (its continued walks
    /// subtract (1 - s)/s a L~).
    std::string roulette = "throughput";
    /// Throughput roulettes: vertices before the first roulette decision (ThroughputRoulette's
    /// min_depth).
    int rr_depth = 3;
    /// Roulette "none": walks stop once the throughput they carry on falls below this.
    float throughput_cutoff = 1e-3f;
    std::string direct = "mis";
    /// The default sampler is Halton with random digit permutations: 1.16x PCG's time per
    /// path, lower error at equal time from 8 spp on (docs/sampling.md), and stratified pixel
    /// samples, which the light's edges need (docs/tracer.md, "Peer comparison: Cycles").
    std::string sampler = "halton";
    std::uint64_t seed = 0;
    /// Band weights H of the roulettes (000 section 2.2): "luminance" (0.3086, 0.6094,
    /// 0.0820) or "mean" (1/3 each, matching an error measured equally over R, G, B).
    std::string roulette_weights = "luminance";
    /// Radiance-estimate roulettes (000 section 2.3): where L~ comes from. "pilot" (default):
    /// the least-squares constant over pilot paths (fitted_radiance_estimate), 000's "data
    /// gathered during a preprocessing phase"; "scene": 000's closed-scene formula
    /// a~ Phi_e / (pi S (1 - a~)). Measured (bench_convergence --analysis): on the open
    /// Cornell box the formula overestimates, goodness d = 1.08 (worse than no estimate, the
    /// case 000 says to avoid), the pilot's d = 0.83; on the furnace, whose radiance is 1
    /// everywhere, the pilot finds L~ = 1 and the roulette adds almost no variance.
    std::string radiance_estimate = "pilot";
    /// Radiance-estimate roulettes: shorten walks by the goodness d of the estimate measured
    /// on pilot paths (ReducedContinuation, 000 section 2.3 lines 1495-1530).
    bool reduce_continuation = false;
    /// Pilot camera paths for "pilot" and reduce_continuation; their time is part of the
    /// render's time. 0: 1/32 of the render's camera paths, at least 1024, at most 4096.
    int pilot_paths = 0;
};

inline const std::vector<std::string>& roulette_names() {
    static const std::vector<std::string> v{"classic", "spectral", "estimate", "spectral+estimate",
                                            "throughput", "throughput+spectral", "throughput+estimate",
                                            "throughput+spectral+estimate", "none"};
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

/// Calls run.template operator()<Env, Points>() with the scene's features: checked once,
/// so that a scene without an environment map or point lights gets a tracer without them.
template <class F>
auto with_features(const Scene<float>& scene, F&& run) {
    const SceneFeatures f = scene.features();
    if (f.environment) return f.point_lights ? run.template operator()<true, true>() : run.template operator()<true, false>();
    return f.point_lights ? run.template operator()<false, true>() : run.template operator()<false, false>();
}

template <class S, class R, class D>
RenderResult render_with(const Scene<float>& scene, const RenderAccel& accel, const R& roulette,
                         const RenderSettings& settings, const S& sampler) {
    return with_features(scene, [&]<bool Env, bool Points>() {
        return PathTracer<RenderAccel, S, R, D, Env, Points>(scene, accel, roulette, settings).render(sampler);
    });
}

/// Calls f.template operator()<D>(settings) with the direct-lighting policy named `direct`.
template <class F>
auto with_direct(const std::string& direct, RenderSettings settings, F&& f) {
    if (direct == "brdf") return f.template operator()<BrdfOnlyDirect>(settings);
    if (direct == "mis") return f.template operator()<MisDirect>(settings);
    if (direct == "importance") settings.estimator = DirectEstimator::importance;
    else if (direct == "correlated") settings.estimator = DirectEstimator::correlated;
    else if (direct == "combined") settings.estimator = DirectEstimator::combined;
    else throw Error("unknown direct lighting '" + direct + "' (brdf, mis, importance, correlated, combined)");
    return f.template operator()<CorrelatedDirect>(settings);
}

template <class S, class R>
RenderResult render_direct(const Scene<float>& scene, const RenderAccel& accel, const R& roulette,
                           const RenderSettings& settings, const std::string& direct, const S& sampler) {
    return with_direct(direct, settings, [&]<class D>(const RenderSettings& st) {
        return render_with<S, R, D>(scene, accel, roulette, st, sampler);
    });
}

inline int pilot_paths(const RenderOptions& o) {
    if (o.pilot_paths > 0) return o.pilot_paths;
    const double paths = double(o.settings.width) * double(o.settings.height) * double(std::max(1, o.settings.spp));
    return int(std::clamp(paths / 32.0, 1024.0, 4096.0));
}

/// A radiance-estimate roulette (000 section 2.3) with its estimate from the scene or from
/// pilot paths, optionally with walks shortened by the estimate's goodness. The pilot's time
/// is counted in the result.
template <class S, class R>
RenderResult render_estimate(const Scene<float>& scene, const RenderAccel& accel, R roulette,
                             const RenderOptions& o, const Rgb<float>& H, const S& sampler) {
    if (o.radiance_estimate != "scene" && o.radiance_estimate != "pilot")
        throw Error("unknown radiance estimate '" + o.radiance_estimate + "' (scene, pilot)");
    const bool pilot = o.radiance_estimate == "pilot";
    if (!pilot) {
        Rgb<float> power, albedo;
        float area;
        scene.radiance_estimate_inputs(power, area, albedo);
        roulette.estimate = global_radiance_estimate(power, area, albedo);
    }
    if (!pilot && !o.reduce_continuation) return render_direct(scene, accel, roulette, o.settings, o.direct, sampler);
    const auto start = std::chrono::steady_clock::now();
    const auto samples = with_direct(o.direct, o.settings, [&]<class D>(const RenderSettings& st) {
        return with_features(scene, [&]<bool Env, bool Points>() {
            return PathTracer<RenderAccel, S, R, D, Env, Points>(scene, accel, roulette, st)
                .pilot_samples(sampler, pilot_paths(o));
        });
    });
    const std::span<const RoulettePilotSample<float, 3>> view(samples);
    if (pilot) roulette.estimate = fitted_radiance_estimate(view);
    const double pilot_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    RenderResult r;
    if (o.reduce_continuation) {
        // d > 1 (an estimate worse than the zero guess) leaves the continuation unchanged.
        const float d = std::clamp(estimate_goodness(view, roulette.estimate, H), 0.05f, 1.0f);
        r = render_direct(scene, accel, ReducedContinuation<float, 3, R>{roulette, d}, o.settings, o.direct, sampler);
    } else {
        r = render_direct(scene, accel, roulette, o.settings, o.direct, sampler);
    }
    r.seconds += pilot_seconds;
    return r;
}

/// Renders with roulette `inner`, or with a radiance estimate on top of it when `estimate`.
template <class S, class R>
RenderResult render_inner(const Scene<float>& scene, const RenderAccel& accel, const R& inner, bool estimate,
                          const RenderOptions& o, const Rgb<float>& H, const S& sampler) {
    if (estimate) return render_estimate(scene, accel, RadianceEstimateRoulette<float, 3, R>{inner, {}}, o, H, sampler);
    return render_direct(scene, accel, inner, o.settings, o.direct, sampler);
}

template <class S>
RenderResult render_roulette(const Scene<float>& scene, const RenderAccel& accel, const RenderOptions& o,
                             const S& sampler) {
    Rgb<float> H;
    if (o.roulette_weights == "luminance") H = Rgb<float>::default_luminance_weights();
    else if (o.roulette_weights == "mean") H = Rgb<float>(1.0f / 3.0f);
    else throw Error("unknown roulette weights '" + o.roulette_weights + "' (luminance, mean)");
    if (o.rr_depth < 0) throw Error("roulette depth must be >= 0, got " + std::to_string(o.rr_depth));
    std::string r = o.roulette == "estimate" ? "classic+estimate" : o.roulette;  // 000's name for it
    const bool estimate = r.ends_with("+estimate");
    if (estimate) r.resize(r.size() - std::string("+estimate").size());
    // In a grey scene every throughput F stays grey, and there 000's spectral rule
    // <F a, H> / <F, H> is exactly the albedo, which the classic rule <a, H> also gives (both
    // weight sets sum to 1, to float rounding), and the H-weighted throughput norm equals the
    // largest band: grey scenes get the non-spectral policies and pay for no spectral
    // bookkeeping.
    const bool grey = scene.features().grey;
    if (grey && r == "spectral") r = "classic";
    if (grey && r == "throughput+spectral") r = "throughput";
    if (r == "classic") return render_inner(scene, accel, ClassicRoulette<float, 3>{H}, estimate, o, H, sampler);
    if (r == "spectral") return render_inner(scene, accel, SpectralRoulette<float, 3>{H}, estimate, o, H, sampler);
    if (r == "throughput" || r == "throughput+spectral") {
        ThroughputRoulette<float, 3> t;
        t.min_depth = o.rr_depth;
        t.weights = H;
        t.norm = r == "throughput" ? ThroughputNorm::max : ThroughputNorm::weighted;
        return render_inner(scene, accel, t, estimate, o, H, sampler);
    }
    if (r == "none" && !estimate) {
        NoRoulette<float, 3> none;
        none.cutoff = o.throughput_cutoff;
        return render_direct(scene, accel, none, o.settings, o.direct, sampler);
    }
    std::string names;
    for (const auto& n : roulette_names()) names += (names.empty() ? "" : ", ") + n;
    throw Error("unknown roulette '" + o.roulette + "' (" + names + ")");
}

}  // namespace detail

/// Renders `scene` with the accelerator `accel` (built over scene.triangles) and the named
/// policies.
inline RenderResult render(const Scene<float>& scene, const RenderAccel& accel, const RenderOptions& o) {
    if (o.sampler == "random") return detail::render_roulette(scene, accel, o, RandomSampler<float>(o.seed));
    // Halton walks (sampling/halton.hpp): "halton" (or "halton-perm") randomized by random
    // digit permutations from tables (fast), "halton-owen" by Owen scrambling, "halton-cp" by a
    // Cranley-Patterson rotation; each point uniform, so every estimator stays unbiased.
    HaltonRandomization randomization;
    if (o.sampler == "halton" || o.sampler == "halton-perm") randomization = HaltonRandomization::digit_permutation;
    else if (o.sampler == "halton-owen") randomization = HaltonRandomization::owen;
    else if (o.sampler == "halton-cp") randomization = HaltonRandomization::cranley_patterson;
    else throw Error("unknown sampler '" + o.sampler + "' (random, halton, halton-perm, halton-owen, halton-cp)");
    // 18 Halton dimensions (the pixel and the first two vertices of a walk), PCG after them:
    // on the Cornell box as low an MSE as 256 dimensions at less cost (docs/sampling.md).
    const std::size_t dims = 18;
    return detail::render_roulette(
        scene, accel, o, HaltonSampler<float>(o.settings.width, o.settings.height, dims, randomization, o.seed));
}

}  // namespace glint
