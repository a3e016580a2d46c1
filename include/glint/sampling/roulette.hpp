// glint/sampling/roulette.hpp: Russian roulette and random BRDF-lobe selection as policies any
// random walk can use, over Spectrum<T, N>.
//
// 000 section 2.1: at a scattering point with w = w_1 + ... + w_n (w_i = the
// elementary BRDF times the cosine, sampled by density p_i), lobe i is selected with
// probability s_i and the walk stops with probability 1 - sum_i s_i. The reflected-radiance
// estimate is L_rr = (W_i / s_i) L_in with, for the three estimators of 000,
//   DIS (decomposition)      W_i = w_i / p_i
//   W   (weighted)           W_i = w s_i / (p_i sum_j s_j)
//   MIS (balance heuristic)  W_i = w s_i / (sum_j s_j p_j)
// (000 section 2.1; the extraction lost the fraction bars and sum limits: repaired from the
// section's derivations). W is unbiased only where every p_i covers the support of w
// (000 section 2.1: "the specular sampling cannot sample the whole domain of the diffuse
// reflection"); DIS and MIS need only that p_i covers w_i, resp. the mixture covers w.
//
// Roulette policies choose the s_i in two parts: the probability s of continuing at all
// (continuation(F, a, depth), a = sum_i a_i the local albedo, depth = scattering vertices
// before this one) and each lobe's share of it (selection_weight(F, a_i)): s_i = s w_i / sum w_j.
//   ClassicRoulette   s_i = <a_i, H>, the weighted mean of the lobe's albedo;
//   SpectralRoulette  s_i = sum_l F(l) W_i(l) H(l) / sum_l F(l) H(l)  (000 section 2.2, lines
//                     1227-1384, with W_i approximated by the lobe albedo a_i, its expectation
//                     under ideal BRDF sampling), F = the walk's throughput so far;
//                     a walk carrying blue light meeting a yellow surface stops;
//   ThroughputRoulette the field's standard rule (pbrt-v4, Mitsuba 3, Cycles): no termination
//                     before a minimum depth k, then s = min(cap, |F a|), a norm of the
//                     throughput the walk would carry on: the max over bands (pbrt-v4,
//                     Mitsuba 3), or 000 section 2.2's H-weighted sum (which, with F = 1 at
//                     the camera, is the spectral rule deferred to depth k);
//   NoRoulette        continue while |F a| stays above a cut-off (biased by what the cut-off
//                     drops; 0: only the tracer's depth cap ends walks);
//   RadianceEstimateRoulette (000 section 2.3): with an estimate L~ of the
//                     incoming radiance, a terminated walk returns a L~ instead of 0 and a
//                     continued one (W_i/s_i) L_in - (1 - s)/s a L~, where a = sum_i a_i is the
//                     local albedo and s = sum_i s_i (alpha = 1/s, beta = -(1-s)/s).
// The scene-wide estimate L~ = a~ Phi_e / (pi S (1 - a~)) counts only the
// reflected power, not the direct emission, so it stays an underestimate.
//
// A step returns ScatterSample{lobe, direction, weight, offset}: the reflected radiance is
// weight * L_in + offset, and the walk multiplies its throughput by `weight` and adds
// throughput * offset to its result. Roulette policies without an estimate have a zero
// offset that compiles away (has_radiance_estimate == false).
#pragma once

#include <algorithm>
#include <array>
#include <concepts>
#include <cstddef>
#include <span>
#include <string>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// Most lobes a MultiLobeBrdf may have (selection probabilities live on the stack).
inline constexpr std::size_t max_brdf_lobes = 8;

/// A roulette policy: how likely a walk with throughput F is to continue at a vertex of local
/// albedo a (`depth` scattering vertices after the camera), how the continuations are shared
/// among the lobes (in proportion to selection_weight(F, a_i)), and what a terminated /
/// continued walk adds.
template <class P, class T, std::size_t N>
concept RoulettePolicy = Scalar<T> && requires(const P& p, const Spectrum<T, N>& F,
                                               const Spectrum<T, N>& a, T s, int depth) {
    { P::has_radiance_estimate } -> std::convertible_to<bool>;
    { p.selection_weight(F, a) } -> std::same_as<T>;
    { p.continuation(F, a, depth) } -> std::same_as<T>;
    { p.terminated(a) } -> std::same_as<Spectrum<T, N>>;
    { p.continued_offset(a, s) } -> std::same_as<Spectrum<T, N>>;
};

/// The zero offsets of a roulette without a radiance estimate.
template <Scalar T, std::size_t N>
struct NoRadianceEstimate {
    static constexpr bool has_radiance_estimate = false;
    Spectrum<T, N> terminated(const Spectrum<T, N>&) const { return Spectrum<T, N>(T(0)); }
    Spectrum<T, N> continued_offset(const Spectrum<T, N>&, T) const { return Spectrum<T, N>(T(0)); }
};

/// Continuation probability from the albedo alone: its weighted mean <a, H> (H = luminance
/// weights by default, or 1/N each for the plain mean).
template <Scalar T, std::size_t N>
struct ClassicRoulette : NoRadianceEstimate<T, N> {
    Spectrum<T, N> weights = Spectrum<T, N>::default_luminance_weights();

    ClassicRoulette() = default;
    explicit ClassicRoulette(const Spectrum<T, N>& H) : weights(H) {}
    static ClassicRoulette mean() { return ClassicRoulette{Spectrum<T, N>(T(1) / T(N))}; }

    T selection_weight(const Spectrum<T, N>&, const Spectrum<T, N>& a) const {
        return std::clamp(a.luminance(weights), T(0), T(1));
    }
    T continuation(const Spectrum<T, N>& F, const Spectrum<T, N>& a, int) const { return selection_weight(F, a); }
};

/// No Russian roulette: a walk continues while the throughput it would carry on, max(F a),
/// stays above `cutoff` (lobes shared by max(F a_i)). With cutoff 0 only the tracer's depth
/// cap ends walks: the reference for how much variance termination adds at all, which bounds
/// what any radiance estimate L~ can gain at equal samples (bench_convergence --analysis).
/// A positive cut-off is the "no roulette" baseline renderers offer: biased by the light it
/// drops, which bench_convergence's error against the reference includes.
template <Scalar T, std::size_t N>
struct NoRoulette : NoRadianceEstimate<T, N> {
    T cutoff = T(0);

    T selection_weight(const Spectrum<T, N>& F, const Spectrum<T, N>& a) const { return std::max((F * a).max(), T(0)); }
    T continuation(const Spectrum<T, N>& F, const Spectrum<T, N>& a, int) const {
        return selection_weight(F, a) > cutoff ? T(1) : T(0);
    }
};

/// 000 section 2.2: s_i = sum F a_i H / sum F H, so that the H-weighted throughput stays
/// constant in expectation. Zero when the walk carries nothing the lobe reflects.
template <Scalar T, std::size_t N>
struct SpectralRoulette : NoRadianceEstimate<T, N> {
    Spectrum<T, N> weights = Spectrum<T, N>::default_luminance_weights();

    SpectralRoulette() = default;
    explicit SpectralRoulette(const Spectrum<T, N>& H) : weights(H) {}

    T selection_weight(const Spectrum<T, N>& F, const Spectrum<T, N>& a) const {
        T num = 0, den = 0;
        for (std::size_t l = 0; l < N; ++l) {
            num += F[l] * a[l] * weights[l];
            den += F[l] * weights[l];
        }
        return den > T(0) ? std::clamp(num / den, T(0), T(1)) : T(0);
    }
    T continuation(const Spectrum<T, N>& F, const Spectrum<T, N>& a, int) const { return selection_weight(F, a); }
};

/// How ThroughputRoulette measures the throughput: the largest band (pbrt-v4, Mitsuba 3) or
/// the H-weighted sum <F, H> (000 section 2.2).
enum class ThroughputNorm { max, weighted };

/// The field's standard roulette: walks always continue before `min_depth` scattering
/// vertices, then with s = min(cap, |F a|), where F a is the throughput the walk carries on
/// in expectation (exactly, for a cosine-sampled diffuse lobe). pbrt-v4 applies
/// min(1, max band) from its second vertex on; Mitsuba 3 min(0.95, max band) from depth 5.
/// After a continuation the throughput's norm is 1 again (F a / s), so the walk ends when
/// the light it carries drops below what it started with, not at the first dark wall.
template <Scalar T, std::size_t N>
struct ThroughputRoulette : NoRadianceEstimate<T, N> {
    int min_depth = 3;
    ThroughputNorm norm = ThroughputNorm::max;
    Spectrum<T, N> weights = Spectrum<T, N>::default_luminance_weights();  // for ThroughputNorm::weighted
    T cap = T(1);

    T selection_weight(const Spectrum<T, N>& F, const Spectrum<T, N>& a) const {
        const Spectrum<T, N> Fa = F * a;
        const T v = norm == ThroughputNorm::max ? Fa.max() : Fa.luminance(weights);
        return v > T(0) ? v : T(0);  // NaN and negative throughputs select nothing
    }
    T continuation(const Spectrum<T, N>& F, const Spectrum<T, N>& a, int depth) const {
        const T v = selection_weight(F, a);
        if (depth < min_depth) return v > T(0) ? T(1) : T(0);
        return std::min(v, cap);
    }
};

/// 000 section 2.3: selection as `Inner` (classic or spectral), but a terminated walk returns
/// a * L~ and a continued one subtracts (1 - s)/s a * L~ (L~ = `estimate`, ideally an
/// underestimate of the incoming radiance).
template <Scalar T, std::size_t N, class Inner = SpectralRoulette<T, N>>
struct RadianceEstimateRoulette {
    static constexpr bool has_radiance_estimate = true;
    Inner inner{};
    Spectrum<T, N> estimate{};

    T selection_weight(const Spectrum<T, N>& F, const Spectrum<T, N>& a) const {
        return inner.selection_weight(F, a);
    }
    T continuation(const Spectrum<T, N>& F, const Spectrum<T, N>& a, int depth) const {
        return inner.continuation(F, a, depth);
    }
    Spectrum<T, N> terminated(const Spectrum<T, N>& a) const { return a * estimate; }
    Spectrum<T, N> continued_offset(const Spectrum<T, N>& a, T s) const {
        return a * estimate * (-(T(1) - s) / s);
    }
};

/// Scene-wide incoming-radiance estimate of 000 section 2.3, per band:
/// L~ = a~ Phi_e / (pi S (1 - a~)) from the emitted power Phi_e, the total surface area S and
/// the mean albedo a~ of a closed scene. Only reflected light is counted (not Phi_e itself),
/// which keeps it an underestimate as 000 recommends.
template <Scalar T, std::size_t N>
Spectrum<T, N> global_radiance_estimate(const Spectrum<T, N>& emitted_power, T total_area,
                                        const Spectrum<T, N>& mean_albedo) {
    if (!(total_area > T(0)) || !std::isfinite(total_area))
        throw Error("glint::global_radiance_estimate: total surface area must be positive and "
                    "finite, got " + std::to_string(total_area));
    Spectrum<T, N> out;
    for (std::size_t l = 0; l < N; ++l) {
        const T a = mean_albedo[l], phi = emitted_power[l];
        if (!(a >= T(0) && a < T(1)))
            throw Error("glint::global_radiance_estimate: mean albedo of band " +
                        std::to_string(l) + " is " + std::to_string(a) +
                        ", must be in [0, 1) for the series a + a^2 + ... to converge");
        if (!(phi >= T(0)) || !std::isfinite(phi))
            throw Error("glint::global_radiance_estimate: emitted power of band " +
                        std::to_string(l) + " must be finite and non-negative");
        out[l] = a * phi / (pi<T> * total_area * (T(1) - a));
    }
    return out;
}

/// One pilot observation for 000 section 2.3: at a scattering point of albedo `albedo`, the
/// one-sample reflected-radiance estimate x = (w/p) L_in that a terminated walk would lose.
template <Scalar T, std::size_t N>
struct RoulettePilotSample {
    Spectrum<T, N> albedo{};
    Spectrum<T, N> reflected{};
};

/// 000 section 2.3 allows L~ to come "from the data gathered during a preprocessing phase".
/// Per band, the constant L~ that minimizes the added variance of termination,
/// sum (x - a L~)^2 over pilot samples, is L~ = sum x a / sum a^2 (least squares; clamped at
/// 0, since 000 asks for a non-negative estimate). Unlike the closed-scene formula below it
/// needs no closed scene: light escaping an open scene makes that formula an overestimate.
template <Scalar T, std::size_t N>
Spectrum<T, N> fitted_radiance_estimate(std::span<const RoulettePilotSample<T, N>> samples) {
    Spectrum<T, N> out(T(0));
    for (std::size_t l = 0; l < N; ++l) {
        double xa = 0, aa = 0;
        for (const auto& s : samples) {
            xa += double(s.reflected[l]) * double(s.albedo[l]);
            aa += double(s.albedo[l]) * double(s.albedo[l]);
        }
        out[l] = aa > 0 ? T(std::max(0.0, xa / aa)) : T(0);
    }
    return out;
}

/// 000 section 2.3's goodness d = E[(x - a L~)^2] / E[x^2] of the estimate L~, in
/// the H-weighted sum over bands, from pilot samples. 1 when there is nothing to measure;
/// above 1 when L~ is worse than the zero guess.
template <Scalar T, std::size_t N>
T estimate_goodness(std::span<const RoulettePilotSample<T, N>> samples, const Spectrum<T, N>& estimate,
                    const Spectrum<T, N>& H) {
    double num = 0, den = 0;
    for (const auto& s : samples) {
        const double x = double(s.reflected.luminance(H));
        const double aL = double((s.albedo * estimate).luminance(H));
        num += (x - aL) * (x - aL);
        den += x * x;
    }
    return den > 0 ? T(num / den) : T(1);
}

/// The least goodness any estimate can reach: E[Var(X | vertex)] / E[X^2], from pilot samples
/// drawn in runs of `repeats` >= 2 at the same vertex (PathTracer::pilot_samples). That is d
/// of the ideal per-vertex estimate L~(x) = E[X | x] / a: what is left is the noise of X itself
/// (the BRDF-sampled direction, the light met there), which no L~ can remove.
template <Scalar T, std::size_t N>
T estimate_goodness_floor(std::span<const RoulettePilotSample<T, N>> samples, std::size_t repeats,
                          const Spectrum<T, N>& H) {
    if (repeats < 2) throw Error("glint::estimate_goodness_floor: needs runs of at least 2 samples per vertex");
    double within = 0, second = 0;
    const std::size_t groups = samples.size() / repeats;
    for (std::size_t g = 0; g < groups; ++g) {
        double sum = 0, sum2 = 0;
        for (std::size_t j = 0; j < repeats; ++j) {
            const double x = double(samples[g * repeats + j].reflected.luminance(H));
            sum += x;
            sum2 += x * x;
        }
        within += (sum2 - sum * sum / double(repeats)) / double(repeats - 1);
        second += sum2 / double(repeats);
    }
    return second > 0 ? T(within / second) : T(1);
}

/// 000 section 2.3: the radiance estimate "can be used to reduce the
/// continuation probability and thus increase the speed". With goodness
/// d = E[((w/p) L_in - a L~)^2] / E[((w/p) L_in)^2] of the estimate, the continuation
/// probability s_new that gives the roulette the same variance as s_old without it solves
/// (1/s_old - 1) E[((w/p) L)^2] = (1/s_new - 1) E[((w/p) L - a L~)^2], so
///   s_new = s_old d / (1 - (1 - d) s_old),
/// and walks get shorter by the factor 1 / (1 - (1 - d) s_old) (000's speedup).
/// (Repaired: the extracted formula reads s_old / ((1 - s_old)/d + 1), which does not give
/// s_new = s_old at d = 1; the form above follows from the equation the text solves.)
/// Wraps a radiance-estimate roulette; d in (0, 1] is measured by the renderer (a pilot
/// pass), d = 1 leaves the roulette unchanged.
template <Scalar T, std::size_t N, class Inner>
struct ReducedContinuation {
    static constexpr bool has_radiance_estimate = Inner::has_radiance_estimate;
    Inner inner{};
    T goodness = T(1);

    T selection_weight(const Spectrum<T, N>& F, const Spectrum<T, N>& a) const {
        return inner.selection_weight(F, a);
    }
    T continuation(const Spectrum<T, N>& F, const Spectrum<T, N>& a, int depth) const {
        const T s = inner.continuation(F, a, depth);
        const T den = T(1) - (T(1) - goodness) * s;
        return den > T(0) ? s * goodness / den : s;
    }
    Spectrum<T, N> terminated(const Spectrum<T, N>& a) const { return inner.terminated(a); }
    Spectrum<T, N> continued_offset(const Spectrum<T, N>& a, T s) const { return inner.continued_offset(a, s); }
};

/// The result of choosing among n lobes and termination with uniform `u`.
template <Scalar T, std::size_t N>
struct LobeSelection {
    std::array<T, max_brdf_lobes> probability{};  // s_i
    std::size_t count = 0;
    T total = 0;          // s = sum s_i (the continuation probability)
    int lobe = -1;        // selected lobe, -1 when the walk terminates
    Spectrum<T, N> offset{};  // radiance-estimate term (zero for the plain roulettes)
    bool terminated() const { return lobe < 0; }
};

/// Selection probabilities s_i = s w_i / sum_j w_j, with w_i = roulette.selection_weight(F,
/// a_i) and s = roulette.continuation(F, sum a_i, depth) clamped to [0, 1]; the choice of a
/// lobe or termination by u in [0,1); the roulette's offset. `albedos` beyond max_brdf_lobes
/// are ignored (precondition: at most max_brdf_lobes).
template <Scalar T, std::size_t N, RoulettePolicy<T, N> R>
LobeSelection<T, N> select_lobe(const R& roulette, const Spectrum<T, N>& throughput,
                                std::span<const Spectrum<T, N>> albedos, T u, int depth) {
    LobeSelection<T, N> sel;
    sel.count = std::min(albedos.size(), max_brdf_lobes);
    Spectrum<T, N> albedo(T(0));
    T shares = 0;
    for (std::size_t i = 0; i < sel.count; ++i) {
        sel.probability[i] = std::max(roulette.selection_weight(throughput, albedos[i]), T(0));
        shares += sel.probability[i];
        albedo += albedos[i];
    }
    const T s = shares > T(0) ? roulette.continuation(throughput, albedo, depth) : T(0);
    sel.total = s > T(0) ? std::min(s, T(1)) : T(0);  // NaN continues nothing
    T cdf = 0;
    for (std::size_t i = 0; i < sel.count; ++i) {
        sel.probability[i] = sel.total > T(0) ? sel.total * (sel.probability[i] / shares) : T(0);
        cdf += sel.probability[i];
        if (sel.lobe < 0 && u < cdf && sel.probability[i] > T(0)) sel.lobe = int(i);
    }
    if constexpr (R::has_radiance_estimate) {
        sel.offset = sel.lobe < 0 ? roulette.terminated(albedo)
                                  : roulette.continued_offset(albedo, sel.total);
    }
    return sel;
}

/// A BRDF made of elementary lobes, seen from a fixed outgoing direction in the local frame
/// (z = normal). w_i = f_r,i cos(theta') is lobe i's scattering density.
template <class M, class T, std::size_t N>
concept MultiLobeBrdf = Scalar<T> && requires(const M& m, std::size_t i, const Vec2<T>& u,
                                              const Vec3<T>& wi) {
    { m.lobe_count() } -> std::convertible_to<std::size_t>;
    { m.albedo(i) } -> std::same_as<Spectrum<T, N>>;  // a_i = integral of w_i
    { m.sample(i, u) } -> std::same_as<Vec3<T>>;      // direction drawn from p_i
    { m.pdf(i, wi) } -> std::convertible_to<T>;       // p_i(wi)
    { m.eval(i, wi) } -> std::same_as<Spectrum<T, N>>;  // w_i(wi)
};

/// The three combined-BRDF estimators of 000 section 2.1.
enum class BrdfSelection { decomposition, weighted, mis };

constexpr const char* short_name(BrdfSelection c) {
    switch (c) {
        case BrdfSelection::decomposition: return "DIS";
        case BrdfSelection::weighted: return "W";
        case BrdfSelection::mis: return "MIS";
    }
    return "?";
}

/// One scattering step: reflected radiance = weight * L_in(direction) + offset.
template <Scalar T, std::size_t N>
struct ScatterSample {
    int lobe = -1;  // -1: terminated
    Vec3<T> direction{0, 0, 1};
    Spectrum<T, N> weight{};  // W_i / s_i, zero when terminated
    Spectrum<T, N> offset{};
    bool terminated() const { return lobe < 0; }
};

/// Russian roulette and lobe selection, then a direction from the chosen lobe and the weight of
/// the DIS, W or MIS estimator. u_select and u_direction are independent uniforms; `depth`
/// counts the walk's scattering vertices before this one.
template <BrdfSelection C, Scalar T, std::size_t N, MultiLobeBrdf<T, N> M, RoulettePolicy<T, N> R>
ScatterSample<T, N> scatter(const M& brdf, const R& roulette, const Spectrum<T, N>& throughput,
                            T u_select, const Vec2<T>& u_direction, int depth) {
    std::array<Spectrum<T, N>, max_brdf_lobes> albedos;
    const std::size_t n = std::min<std::size_t>(brdf.lobe_count(), max_brdf_lobes);
    for (std::size_t i = 0; i < n; ++i) albedos[i] = brdf.albedo(i);
    const LobeSelection<T, N> sel =
        select_lobe(roulette, throughput, std::span<const Spectrum<T, N>>(albedos.data(), n), u_select, depth);
    ScatterSample<T, N> out;
    out.offset = sel.offset;
    if (sel.terminated()) return out;
    const auto i = std::size_t(sel.lobe);
    out.lobe = sel.lobe;
    out.direction = brdf.sample(i, u_direction);
    if constexpr (C == BrdfSelection::decomposition) {
        const T p = T(brdf.pdf(i, out.direction)) * sel.probability[i];
        if (p > T(0)) out.weight = brdf.eval(i, out.direction) / p;
    } else {
        Spectrum<T, N> w(T(0));
        T mixture = 0;
        for (std::size_t j = 0; j < n; ++j) {
            w += brdf.eval(j, out.direction);
            if constexpr (C == BrdfSelection::mis) mixture += sel.probability[j] * T(brdf.pdf(j, out.direction));
        }
        if constexpr (C == BrdfSelection::weighted) mixture = T(brdf.pdf(i, out.direction)) * sel.total;
        if (mixture > T(0)) out.weight = w / mixture;
    }
    return out;
}

}  // namespace glint
