// render_policies/dispatch.hpp: the steps of the choice by name that the policy translation
// units share. render_policies<Accel, S, D> is declared here and defined in
// dispatch_impl.hpp; each translation unit that CMakeLists.txt generates instantiates it for
// one accelerator, sampler and direct-lighting policy (with every roulette and scene feature
// those can meet), so a caller of render() compiles none of the tracers.
#pragma once

#include <string>

#include <glint/core/error.hpp>
#include <glint/tracer/correlated_direct.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/path_tracer.hpp>

#include "render_options.hpp"

namespace glint_cli {

/// Renders with accelerator Accel, sampler S (the prototype `sampler`) and the direct-lighting
/// policy `direct`; the roulette by o.roulette, the scene's features checked once.
template <class Accel, class S, class D>
RenderResult render_policies(const Scene<float>& scene, const Accel& accel, const RenderOptions& o, const D& direct,
                             const S& sampler);

/// Calls f(policy) with the direct-lighting policy named `direct`, built for the scene: the
/// estimator is chosen here, once, by the name.
template <class F>
auto with_direct(const std::string& direct, const Scene<float>& scene, const RenderSettings& settings, F&& f) {
    if (direct == "brdf") return f(BrdfOnlyDirect<float>(scene, settings));
    if (direct == "mis") return f(MisDirect<float>(scene, settings));
    DirectEstimator e;
    if (direct == "importance") e = DirectEstimator::importance;
    else if (direct == "correlated") e = DirectEstimator::correlated;
    else if (direct == "combined") e = DirectEstimator::combined;
    else throw Error("unknown direct lighting '" + direct + "' (brdf, mis, importance, correlated, combined)");
    return f(CorrelatedDirect<float>(scene, settings, e));
}

}  // namespace glint_cli
