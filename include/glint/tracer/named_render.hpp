// glint/tracer/named_render.hpp: the path tracer's policies chosen by name, one table per
// choice ({name, help, make}, tracer/choice.hpp), and render_named(), which renders a scene
// with the policies a NamedRender names: what glint-render's flags, bench_convergence and the
// tracer tests choose by.
//
// Types are chosen only where they pay in the hot loop: the direct-lighting policy and the
// sampler become a std::variant here and one std::visit picks the PathTracer instantiation
// (4 x 2: Fernandez 2004's systems share one type, ManyLightDirect); the accelerator
// (AnyAccel, tracer/any_accel.hpp), the roulette rule, the BRDF selection and the scene's
// features are values. check_names() checks
// every name at once, so that a command line can reject an unknown one before it reads a file
// or builds a tree.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>

#include <glint/core/error.hpp>
#include <glint/lights/many_light_direct.hpp>
#include <glint/sampling/halton.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/any_accel.hpp>
#include <glint/tracer/choice.hpp>
#include <glint/tracer/correlated_direct.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// What the roulette names are made from: the band weights H, the throughput rule's first
/// depth, the "none" rule's cut-off, and whether the scene is grey (SceneFeatures::grey).
template <Scalar T>
struct RouletteParams {
    Rgb<T> weights = Rgb<T>::default_luminance_weights();  ///< Band weights H that turn an RGB throughput into a scalar; default luminance.
    int min_depth = 3;      ///< Throughput rules: path vertices before the first roulette decision.
    T cutoff = T(1e-3);     ///< "none" rule: throughput (weighted by H) below which a walk stops.
    bool grey = false;      ///< Whether every material of the scene is grey (SceneFeatures::grey).
};

/// The roulette rules by name. In a grey scene every throughput F stays grey, and there the
/// spectral rule <F a, H> / <F, H> is exactly the albedo, which the classic rule <a, H> also
/// gives (both weight sets sum to 1, to float rounding), and the H-weighted throughput norm
/// equals the largest band: grey scenes get the non-spectral rules. Any name may end in
/// "+estimate" (Szécsi 2009, §2.3's radiance estimate on top; "estimate" = "classic+estimate").
template <Scalar T>
std::span<const Choice<Roulette<T, 3> (*)(const RouletteParams<T>&)>> roulette_choices() {
    using R = Roulette<T, 3>;
    using P = const RouletteParams<T>&;
    static constexpr Choice<R (*)(P)> table[] = {
        {"throughput", "the field's rule: s = min(1, max F a) from --rr-depth", [](P p) {
             return R::throughput(ThroughputNorm::max, p.min_depth, T(1), p.weights);
         }},
        {"throughput+spectral", "the same with Szecsi 2009 2.2's norm <F a, H>", [](P p) {
             return R::throughput(p.grey ? ThroughputNorm::max : ThroughputNorm::weighted, p.min_depth, T(1), p.weights);
         }},
        {"classic", "Szecsi 2009 2.1: s = <a, H>", [](P p) { return R::classic(p.weights); }},
        {"spectral", "Szecsi 2009 2.2: s = <F a, H> / <F, H>",
         [](P p) { return p.grey ? R::classic(p.weights) : R::spectral(p.weights); }},
        {"none", "no roulette: walks stop once max F a < 1e-3", [](P p) { return R::none(p.cutoff); }},
    };
    return table;
}

/// A roulette name split into its rule's table entry and whether "+estimate" follows it.
template <Scalar T>
std::pair<const Choice<Roulette<T, 3> (*)(const RouletteParams<T>&)>*, bool> find_roulette(std::string_view name) {
    std::string rule(name == "estimate" ? "classic+estimate" : name);
    const bool estimate = rule.ends_with("+estimate");
    if (estimate) rule.resize(rule.size() - std::string_view("+estimate").size());
    for (const auto& c : roulette_choices<T>())
        if (c.name == rule) return {&c, estimate};
    throw Error("unknown roulette '" + std::string(name) + "' (" + choice_names(roulette_choices<T>()) +
                ", estimate; each with +estimate)");
}

inline std::span<const Choice<BrdfSelection>> selection_choices() {
    static constexpr Choice<BrdfSelection> table[] = {
        {"mis", "the balance heuristic over the lobes (Szecsi 2009 2.1)", BrdfSelection::mis},
        {"dis", "decomposition: each lobe by its own density", BrdfSelection::decomposition},
        {"w", "weighted (biased where a lobe's density misses the others)", BrdfSelection::weighted},
    };
    return table;
}

namespace detail {
/// The width / height of the image a named render makes (the view the LIE and sparse samples cover).
inline double image_aspect(const RenderSettings& image) {
    return double(std::max(image.width, 1)) / double(std::max(image.height, 1));
}
/// The LIEs of a named render: construction samples of the image's view, 4 per pixel and at
/// most 2^15 (the whole budget from 91 x 91 pixels up; a small preview does not pay for more).
inline LieSettings factory_lie_settings(const RenderSettings& image) {
    LieSettings s;
    const long pixels = long(std::max(image.width, 1)) * long(std::max(image.height, 1));
    s.samples = int(std::clamp(4 * pixels, 1024L, 1L << 15));
    s.aspect = image_aspect(image);
    return s;
}
/// Sparse sampling in `mode` over the image's view.
inline SparseSettings factory_sparse_settings(SparseMode mode, const RenderSettings& image) {
    SparseSettings s;
    s.mode = mode;
    s.aspect = image_aspect(image);
    return s;
}
}  // namespace detail

/// The direct-lighting policies a name can choose; the table's entries make one from the
/// scene, the accelerator over its triangles (the rays of the LIE's and the sparse samples'
/// construction), the tracer's and the image's settings.
template <Scalar T>
using DirectChoice = std::variant<BrdfOnlyDirect<T>, MisDirect<T>, CorrelatedDirect<T>, ManyLightDirect<T>>;

template <Scalar T>
std::span<const Choice<DirectChoice<T> (*)(const Scene<T>&, const AnyAccel&, const PathTracerSettings<T>&, const RenderSettings&)>>
direct_choices() {
    using D = DirectChoice<T>;
    using Sc = const Scene<T>&;
    using Ac = const AnyAccel&;
    using St = const PathTracerSettings<T>&;
    using Im = const RenderSettings&;
    static constexpr Choice<D (*)(Sc, Ac, St, Im)> table[] = {
        {"mis", "light and BRDF samples by the balance heuristic; lights by power", [](Sc s, Ac, St t, Im) { return D(MisDirect<T>(s, t)); }},
        {"power", "the same as mis (Cycles 3.4's light selection)", [](Sc s, Ac, St t, Im) { return D(MisDirect<T>(s, t)); }},
        {"tree", "the same, lights by the stochastic light tree (Conty Estevez and Kulla 2018)",
         [](Sc s, Ac, St t, Im) { return D(MisDirect<T>(s, t, LightSelection::tree)); }},
        {"brdf", "no light sampling: emission counts where the walk meets it",
         [](Sc s, Ac, St t, Im) { return D(BrdfOnlyDirect<T>(s, t)); }},
        {"importance", "Szecsi 2009 3.2's light samples, lambda = 0",
         [](Sc s, Ac, St t, Im) { return D(CorrelatedDirect<T>(s, t, DirectEstimator::importance)); }},
        {"correlated", "Szecsi 2009 3.2's correlated estimator, lambda = 1",
         [](Sc s, Ac, St t, Im) { return D(CorrelatedDirect<T>(s, t, DirectEstimator::correlated)); }},
        {"combined", "Szecsi 2009 3.2's combined estimator, lambda pooled",
         [](Sc s, Ac, St t, Im) { return D(CorrelatedDirect<T>(s, t, DirectEstimator::combined)); }},
        {"lie", "Fernandez 2004 ch. 3's local illumination environments (biased where unsampled)",
         [](Sc s, Ac a, St, Im i) { return D(ManyLightDirect<T>(LieDirect<T>(s, a, detail::factory_lie_settings(i), false))); }},
        {"lie-mask", "the same with Weber masking (drops up to 2% per cell)",
         [](Sc s, Ac a, St, Im i) { return D(ManyLightDirect<T>(LieDirect<T>(s, a, detail::factory_lie_settings(i), true))); }},
        {"cuts", "Fernandez 2004 5.2's dense light cuts over every light, area lights as points (biased)",
         [](Sc s, Ac, St t, Im) { return D(ManyLightDirect<T>(CutDirect<T>(s, t))); }},
        {"sparse-interp", "Fernandez 2004 5.3.1's interpolation of 5000 sample cuts at primary hits (blurs shadow edges)",
         [](Sc s, Ac a, St, Im i) {
             return D(ManyLightDirect<T>(SparseDirect<T>(s, a, LightPointOptions<T>{}, detail::factory_sparse_settings(SparseMode::interpolate, i))));
         }},
        {"sparse-recon", "Fernandez 2004 5.3.2's reconstruction cuts from 5000 sample cuts at primary hits (biased)",
         [](Sc s, Ac a, St, Im i) {
             return D(ManyLightDirect<T>(SparseDirect<T>(s, a, LightPointOptions<T>{}, detail::factory_sparse_settings(SparseMode::reconstruct, i))));
         }},
    };
    return table;
}

/// The samplers a name can choose.
template <Scalar T>
using SamplerChoice = std::variant<RandomSampler<T>, HaltonSampler<T>>;

namespace detail {
/// A Halton sampler of render_halton_dims dimensions, PCG after them.
template <Scalar T>
SamplerChoice<T> halton_sampler(int w, int h, std::uint64_t seed, HaltonRandomization r) {
    return SamplerChoice<T>(HaltonSampler<T>(w, h, render_halton_dims, r, seed));
}
}  // namespace detail

template <Scalar T>
std::span<const Choice<SamplerChoice<T> (*)(int, int, std::uint64_t)>> sampler_choices() {
    using S = SamplerChoice<T>;
    using H = HaltonRandomization;
    static constexpr Choice<S (*)(int, int, std::uint64_t)> table[] = {
        {"halton", "Halton with random digit permutations (fast)",
         [](int w, int h, std::uint64_t s) { return detail::halton_sampler<T>(w, h, s, H::digit_permutation); }},
        {"halton-perm", "the same", [](int w, int h, std::uint64_t s) { return detail::halton_sampler<T>(w, h, s, H::digit_permutation); }},
        {"halton-owen", "Halton, Owen-scrambled", [](int w, int h, std::uint64_t s) { return detail::halton_sampler<T>(w, h, s, H::owen); }},
        {"halton-cp", "Halton, Cranley-Patterson rotated",
         [](int w, int h, std::uint64_t s) { return detail::halton_sampler<T>(w, h, s, H::cranley_patterson); }},
        {"random", "independent PCG32 numbers", [](int, int, std::uint64_t s) { return S(RandomSampler<T>(s)); }},
    };
    return table;
}

/// Where the radiance estimate L~ of a "+estimate" roulette comes from.
enum class EstimateSource { pilot, scene };

inline std::span<const Choice<EstimateSource>> estimate_choices() {
    static constexpr Choice<EstimateSource> table[] = {
        {"pilot", "least squares over pilot paths (fitted_radiance_estimate)", EstimateSource::pilot},
        {"scene", "Szecsi 2009 2.3's closed-scene formula", EstimateSource::scene},
    };
    return table;
}

template <Scalar T>
std::span<const Choice<Rgb<T> (*)()>> weights_choices() {
    static constexpr Choice<Rgb<T> (*)()> table[] = {
        {"luminance", "H = (0.3086, 0.6094, 0.0820)", [] { return Rgb<T>::default_luminance_weights(); }},
        {"mean", "H = 1/3 each", [] { return Rgb<T>(T(1) / T(3)); }},
    };
    return table;
}

/// A render's settings with its policies by name (each table's first entry is the default).
template <Scalar T = float>
struct NamedRender {
    /// Image and run settings for the Renderer (tracer/renderer.hpp).
    RenderSettings image{};
    /// The tracer's settings; render_named sets roulette and selection from the names.
    PathTracerSettings<T> tracer{};
    /// Russian-roulette rule, a name of the roulette table (optionally ending in "+estimate").
    std::string roulette = "throughput", direct = "mis", selection = "mis", sampler = "halton";  ///< Sampler, a name of the sampler table (e.g. "halton").
    /// \var direct
    /// Direct-lighting policy, a name of the direct-lighting table (e.g. "mis").

    /// \var selection
    /// BRDF-selection rule at a vertex, a name of the selection table (e.g. "mis").

    /// Band weights H for the roulette, a name of the weights table (e.g. "luminance").
    std::string weights = "luminance", estimate = "pilot";  ///< Source of the radiance estimate of "+estimate" roulettes (e.g. "pilot").
    int rr_depth = 3;               ///< Throughput rules: vertices before the first decision.
    T throughput_cutoff = T(1e-3);  ///< Roulette "none": the throughput below which a walk stops.
    std::uint64_t seed = 0;         ///< Seed of the samplers' random streams.
    /// "+estimate" roulettes: shorten walks by the goodness d of the estimate measured on pilot
    /// paths (Roulette::goodness, Szécsi 2009, §2.3).
    bool reduce_continuation = false;
    /// Pilot camera paths (their time counts in the render's); 0: 1/32 of the render's camera
    /// paths, at least 1024, at most 4096.
    int pilot_paths = 0;
};

/// The table entries a NamedRender names, each looked up once (resolve_names).
template <Scalar T>
struct NamedChoices {
    /// The roulette table's entry, which makes the Roulette from RouletteParams.
    const Choice<Roulette<T, 3> (*)(const RouletteParams<T>&)>* roulette;
    bool estimate;  ///< Whether the roulette name ends in "+estimate".
    /// Makes the direct-lighting policy for a scene, its accelerator, tracer settings and image settings.
    DirectChoice<T> (*direct)(const Scene<T>&, const AnyAccel&, const PathTracerSettings<T>&, const RenderSettings&);
    BrdfSelection selection;  ///< The BRDF-selection rule named.
    /// Makes the sampler from the image width and height in pixels and the seed.
    SamplerChoice<T> (*sampler)(int, int, std::uint64_t);
    /// Returns the band weights H named.
    Rgb<T> (*weights)();
    EstimateSource estimate_source;  ///< Where "+estimate" roulettes take their radiance estimate.
};

/// Looks up every name of `o`; throws glint::Error for the first unknown one, naming it and
/// the known ones.
template <Scalar T>
NamedChoices<T> resolve_names(const NamedRender<T>& o) {
    const auto roulette = find_roulette<T>(o.roulette);
    NamedChoices<T> c{roulette.first,
                      roulette.second,
                      find_choice(direct_choices<T>(), "direct lighting", o.direct).make,
                      find_choice(selection_choices(), "BRDF selection", o.selection).make,
                      find_choice(sampler_choices<T>(), "sampler", o.sampler).make,
                      find_choice(weights_choices<T>(), "roulette weights", o.weights).make,
                      find_choice(estimate_choices(), "radiance estimate", o.estimate).make};
    if (o.rr_depth < 0) throw Error("roulette depth must be >= 0, got " + std::to_string(o.rr_depth));
    return c;
}

/// Throws glint::Error for the first unknown name of `o`, naming it and the known ones.
template <Scalar T>
void check_names(const NamedRender<T>& o) {
    resolve_names(o);
}

namespace detail {

template <Scalar T>
int pilot_paths(const NamedRender<T>& o) {
    if (o.pilot_paths > 0) return o.pilot_paths;
    const double paths = double(o.image.width) * double(o.image.height) * double(std::max(1, o.image.spp));
    return int(std::clamp(paths / 32.0, 1024.0, 4096.0));
}

/// Renders with the tracer's policies fixed; with a radiance estimate (`estimate`), first from
/// the scene or from pilot paths, optionally with walks shortened by its goodness. The pilot's
/// time is counted in the result.
template <class Accel, class S, class D, Scalar T>
RenderResult render_policies(const Scene<T>& scene, const Accel& accel, const D& direct, const S& sampler,
                             PathTracerSettings<T> ts, const NamedChoices<T>& names, const NamedRender<T>& o) {
    using Tracer = PathTracer<Accel, S, D>;
    const MisEnvironment<T> env(scene);
    if (!names.estimate) return render_image(scene, o.image, Tracer(scene, accel, direct, env, ts), sampler);
    const bool pilot = names.estimate_source == EstimateSource::pilot;
    if (!pilot) {
        Rgb<T> power, albedo;
        T area;
        scene.radiance_estimate_inputs(power, area, albedo);
        ts.roulette.estimate = global_radiance_estimate(power, area, albedo);
        if (!o.reduce_continuation) return render_image(scene, o.image, Tracer(scene, accel, direct, env, ts), sampler);
    }
    const auto start = std::chrono::steady_clock::now();
    const auto samples = Tracer(scene, accel, direct, env, ts).pilot_samples(o.image, sampler, pilot_paths(o));
    const std::span<const RoulettePilotSample<T, 3>> view(samples);
    if (pilot) ts.roulette.estimate = fitted_radiance_estimate(view);
    // d > 1 (an estimate worse than the zero guess) leaves the continuation unchanged.
    if (o.reduce_continuation)
        ts.roulette.goodness = std::clamp(estimate_goodness(view, ts.roulette.estimate, ts.roulette.weights), T(0.05), T(1));
    const double pilot_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    RenderResult r = render_image(scene, o.image, Tracer(scene, accel, direct, env, ts), sampler);
    r.seconds += pilot_seconds;
    return r;
}

}  // namespace detail

/// Renders `scene` with accelerator `accel` (built over scene.triangles; any tree through
/// any_accel_view(), tracer/any_accel.hpp) and the policies `o` names (every name looked up
/// before anything is built).
template <Scalar T>
RenderResult render_named(const Scene<T>& scene, const AnyAccel& accel, const NamedRender<T>& o) {
    static_assert(std::is_same_v<T, float>, "glint::render_named: AnyAccel traces float rays");
    const NamedChoices<T> names = resolve_names(o);
    PathTracerSettings<T> ts = o.tracer;
    ts.selection = names.selection;
    ts.roulette = names.roulette->make({names.weights(), o.rr_depth, o.throughput_cutoff, scene.features().grey});
    const DirectChoice<T> direct = names.direct(scene, accel, ts, o.image);
    const SamplerChoice<T> sampler = names.sampler(o.image.width, o.image.height, o.seed);
    return std::visit(
        [&](const auto& d, const auto& s) { return detail::render_policies(scene, accel, d, s, ts, names, o); }, direct,
        sampler);
}

}  // namespace glint
