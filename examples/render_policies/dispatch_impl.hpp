// render_policies/dispatch_impl.hpp: the definition of render_policies (dispatch.hpp): the
// roulette by name, then the scene's features, then one PathTracer instantiation per
// combination. Included only by the generated policy translation units and by
// bench_convergence's analysis (which instantiates its own few tracers).
#pragma once

#include <algorithm>
#include <chrono>
#include <span>
#include <string>

#include <glint/sampling/roulette.hpp>

#include "dispatch.hpp"

namespace glint_cli {
namespace steps {

/// Calls run.template operator()<E, Points>() with the scene's features: the environment
/// policy E (MisEnvironment or NoEnvironment) and whether there are point lights, checked once,
/// so that a scene without an environment map or point lights gets a tracer without them.
template <class F>
auto with_features(const Scene<float>& scene, F&& run) {
    using Mis = MisEnvironment<float>;
    using None = NoEnvironment<float>;
    const SceneFeatures f = scene.features();
    if (f.environment) return f.point_lights ? run.template operator()<Mis, true>() : run.template operator()<Mis, false>();
    return f.point_lights ? run.template operator()<None, true>() : run.template operator()<None, false>();
}

template <class Accel, class S, class R, class D>
RenderResult render_with(const Scene<float>& scene, const Accel& accel, const R& roulette, const D& direct,
                         const RenderSettings& settings, const S& sampler) {
    return with_features(scene, [&]<class E, bool Points>() {
        const PathTracer<Accel, S, R, D, E, Points> tracer(scene, accel, roulette, direct, E(scene), settings);
        return render_image(scene, settings, tracer, sampler);
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
template <class Accel, class S, class R, class D>
RenderResult render_estimate(const Scene<float>& scene, const Accel& accel, R roulette, const D& direct,
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
    if (!pilot && !o.reduce_continuation) return render_with<Accel, S, R, D>(scene, accel, roulette, direct, o.settings, sampler);
    const auto start = std::chrono::steady_clock::now();
    const auto samples = with_features(scene, [&]<class E, bool Points>() {
        return PathTracer<Accel, S, R, D, E, Points>(scene, accel, roulette, direct, E(scene), o.settings)
            .pilot_samples(sampler, pilot_paths(o));
    });
    const std::span<const RoulettePilotSample<float, 3>> view(samples);
    if (pilot) roulette.estimate = fitted_radiance_estimate(view);
    const double pilot_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    RenderResult r;
    if (o.reduce_continuation) {
        // d > 1 (an estimate worse than the zero guess) leaves the continuation unchanged.
        const float d = std::clamp(estimate_goodness(view, roulette.estimate, H), 0.05f, 1.0f);
        using Reduced = ReducedContinuation<float, 3, R>;
        r = render_with<Accel, S, Reduced, D>(scene, accel, Reduced{roulette, d}, direct, o.settings, sampler);
    } else {
        r = render_with<Accel, S, R, D>(scene, accel, roulette, direct, o.settings, sampler);
    }
    r.seconds += pilot_seconds;
    return r;
}

/// Renders with roulette `inner`, or with a radiance estimate on top of it when `estimate`.
template <class Accel, class S, class R, class D>
RenderResult render_inner(const Scene<float>& scene, const Accel& accel, const R& inner, bool estimate, const D& direct,
                          const RenderOptions& o, const Rgb<float>& H, const S& sampler) {
    using Estimate = RadianceEstimateRoulette<float, 3, R>;
    if (estimate) return render_estimate<Accel, S, Estimate, D>(scene, accel, Estimate{inner, {}}, direct, o, H, sampler);
    return render_with<Accel, S, R, D>(scene, accel, inner, direct, o.settings, sampler);
}

/// The band weights H named by o.roulette_weights.
inline Rgb<float> roulette_weights(const RenderOptions& o) {
    if (o.roulette_weights == "luminance") return Rgb<float>::default_luminance_weights();
    if (o.roulette_weights == "mean") return Rgb<float>(1.0f / 3.0f);
    throw Error("unknown roulette weights '" + o.roulette_weights + "' (luminance, mean)");
}

}  // namespace steps

template <class Accel, class S, class D>
RenderResult render_policies(const Scene<float>& scene, const Accel& accel, const RenderOptions& o, const D& direct,
                             const S& sampler) {
    const Rgb<float> H = steps::roulette_weights(o);
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
    using steps::render_inner;
    if (r == "classic") {
        using Classic = ClassicRoulette<float, 3>;
        return render_inner<Accel, S, Classic, D>(scene, accel, Classic{H}, estimate, direct, o, H, sampler);
    }
    if (r == "spectral") {
        using Spectral = SpectralRoulette<float, 3>;
        return render_inner<Accel, S, Spectral, D>(scene, accel, Spectral{H}, estimate, direct, o, H, sampler);
    }
    if (r == "throughput" || r == "throughput+spectral") {
        ThroughputRoulette<float, 3> t;
        t.min_depth = o.rr_depth;
        t.weights = H;
        t.norm = r == "throughput" ? ThroughputNorm::max : ThroughputNorm::weighted;
        return render_inner<Accel, S, ThroughputRoulette<float, 3>, D>(scene, accel, t, estimate, direct, o, H, sampler);
    }
    if (r == "none" && !estimate) {
        NoRoulette<float, 3> none;
        none.cutoff = o.throughput_cutoff;
        return steps::render_with<Accel, S, NoRoulette<float, 3>, D>(scene, accel, none, direct, o.settings, sampler);
    }
    std::string names;
    for (const auto& n : roulette_names()) names += (names.empty() ? "" : ", ") + n;
    throw Error("unknown roulette '" + o.roulette + "' (" + names + ")");
}

}  // namespace glint_cli
