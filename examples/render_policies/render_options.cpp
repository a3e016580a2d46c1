// render_policies/render_options.cpp: the names, and render(): the sampler and the direct
// lighting by name, then the tracers one generated translation unit instantiates.
#include <glint/sampling/halton.hpp>
#include <glint/sampling/sampler.hpp>

#include "dispatch.hpp"
#include "render_options.hpp"

namespace glint_cli {

// The instantiations the generated translation units provide (CMakeLists.txt).
#define GLINT_CLI_EXTERN_ONE(A, S, D)                                                                     \
    extern template RenderResult render_policies<A, S, D>(const Scene<float>&, const A&, const RenderOptions&, \
                                                          const D&, const S&);
#define GLINT_CLI_EXTERN(A, S)                          \
    GLINT_CLI_EXTERN_ONE(A, S, BrdfOnlyDirect<float>)   \
    GLINT_CLI_EXTERN_ONE(A, S, MisDirect<float>)        \
    GLINT_CLI_EXTERN_ONE(A, S, CorrelatedDirect<float>)
GLINT_CLI_EXTERN(RenderAccel, RandomSampler<float>)
GLINT_CLI_EXTERN(RenderAccel, HaltonSampler<float>)
GLINT_CLI_EXTERN(AnyAccel, RandomSampler<float>)
GLINT_CLI_EXTERN(AnyAccel, HaltonSampler<float>)
#undef GLINT_CLI_EXTERN
#undef GLINT_CLI_EXTERN_ONE

const std::vector<std::string>& roulette_names() {
    static const std::vector<std::string> v{"classic", "spectral", "estimate", "spectral+estimate",
                                            "throughput", "throughput+spectral", "throughput+estimate",
                                            "throughput+spectral+estimate", "none"};
    return v;
}

const std::vector<std::string>& direct_names() {
    static const std::vector<std::string> v{"brdf", "mis", "importance", "correlated", "combined"};
    return v;
}

BrdfSelection parse_selection(const std::string& s) {
    if (s == "dis") return BrdfSelection::decomposition;
    if (s == "w") return BrdfSelection::weighted;
    if (s == "mis") return BrdfSelection::mis;
    throw Error("unknown BRDF selection '" + s + "' (dis, w, mis)");
}

namespace {

template <class Accel, class S>
RenderResult render_sampler(const Scene<float>& scene, const Accel& accel, const RenderOptions& o, const S& sampler) {
    return with_direct(o.direct, scene, o.settings, [&]<class D>(const D& direct) {
        return render_policies<Accel, S, D>(scene, accel, o, direct, sampler);
    });
}

template <class Accel>
RenderResult render_any(const Scene<float>& scene, const Accel& accel, const RenderOptions& o) {
    if (o.sampler == "random") return render_sampler(scene, accel, o, RandomSampler<float>(o.seed));
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
    return render_sampler(scene, accel, o,
                          HaltonSampler<float>(o.settings.width, o.settings.height, dims, randomization, o.seed));
}

}  // namespace

RenderResult render(const Scene<float>& scene, const RenderAccel& accel, const RenderOptions& o) {
    return render_any(scene, accel, o);
}

RenderResult render(const Scene<float>& scene, const AnyAccel& accel, const RenderOptions& o) {
    return render_any(scene, accel, o);
}

}  // namespace glint_cli
