// glint/sampling/roulette.hpp: Russian roulette and random BRDF-lobe selection for any random
// walk, over Spectrum<T, N>.
//
// Szécsi 2009, §2.1: at a scattering point with w = w_1 + ... + w_n (w_i = the elementary BRDF
// times the cosine, sampled by density p_i), lobe i is selected with probability s_i and the
// walk stops with probability 1 - sum_i s_i. The reflected-radiance estimate is
// L_rr = (W_i / s_i) L_in with, for the three estimators of §2.1,
//   DIS (decomposition)      W_i = w_i / p_i
//   W   (weighted)           W_i = w s_i / (p_i sum_j s_j)
//   MIS (balance heuristic)  W_i = w s_i / (sum_j s_j p_j)
// (repaired from the section's derivations: the extracted text lost the fraction bars and sum
// limits). W is unbiased only where every p_i covers the support of w ("the specular sampling
// cannot sample the whole domain of the diffuse reflection"); DIS and MIS need only that p_i
// covers w_i, resp. the mixture covers w.
//
// A roulette chooses the s_i in two parts: the probability s of continuing at all
// (continuation(F, a, depth), a = sum_i a_i the local albedo, depth = scattering vertices
// before this one) and each lobe's share of it (selection_weight(F, a_i)): s_i = s w_i / sum w_j.
// Roulette is one small value with a run-time rule (a predictable branch per vertex):
//   classic     s_i = <a_i, H>, the weighted mean of the lobe's albedo;
//   spectral    s_i = sum_l F(l) a_i(l) H(l) / sum_l F(l) H(l) (Szécsi 2009, §2.2, with W_i
//               approximated by the lobe albedo a_i, its expectation under ideal BRDF
//               sampling), F = the walk's throughput so far: a walk carrying blue light
//               meeting a yellow surface stops;
//   throughput  the field's standard rule (pbrt-v4, Mitsuba 3, Cycles): no termination before
//               min_depth vertices, then s = min(cap, |F a|), a norm of the throughput the
//               walk would carry on: the max over bands (pbrt-v4, Mitsuba 3), or §2.2's
//               H-weighted sum (which, with F = 1 at the camera, is the spectral rule deferred
//               to depth min_depth);
//   none        continue while max(F a) stays above a cut-off (biased by what the cut-off
//               drops; 0: only the tracer's depth cap ends walks).
// Any rule takes §2.3's radiance estimate L~ (`estimate`): a terminated walk returns a L~
// instead of 0 and a continued one (W_i/s_i) L_in - (1 - s)/s a L~ (alpha = 1/s,
// beta = -(1-s)/s); and §2.3's reduced continuation by the estimate's goodness d (`goodness`).
// Their identity values (L~ = 0, d = 1) give zero offsets and leave s unchanged.
//
// A step returns ScatterSample{lobe, direction, weight, offset}: the reflected radiance is
// weight * L_in + offset; the walk multiplies its throughput by `weight` and adds
// throughput * offset to its result.
#pragma once

#include <algorithm>
#include <array>
#include <concepts>
#include <cstddef>
#include <span>

#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/sampling/radiance_estimate.hpp>

namespace glint {

/// Most lobes a MultiLobeBrdf may have (selection probabilities live on the stack).
inline constexpr std::size_t max_brdf_lobes = 8;

/// What select_lobe and scatter ask of a roulette: how likely a walk with throughput F is to
/// continue at a vertex of local albedo a (`depth` scattering vertices after the camera), how
/// the continuations are shared among the lobes (in proportion to selection_weight(F, a_i)),
/// and what a terminated / continued walk adds (zero without a radiance estimate).
template <class P, class T, std::size_t N>
concept RoulettePolicy = Scalar<T> && requires(const P& p, const Spectrum<T, N>& F,
                                               const Spectrum<T, N>& a, T s, int depth) {
    { p.selection_weight(F, a) } -> std::same_as<T>;
    { p.continuation(F, a, depth) } -> std::same_as<T>;
    { p.terminated(a) } -> std::same_as<Spectrum<T, N>>;
    { p.continued_offset(a, s) } -> std::same_as<Spectrum<T, N>>;
};

/// The rules of Roulette.
enum class RouletteRule { classic, spectral, throughput, none };

/// How the throughput rule measures the throughput: the largest band (pbrt-v4, Mitsuba 3) or
/// the H-weighted sum <F, H> (Szécsi 2009, §2.2).
enum class ThroughputNorm { max, weighted };

/// A Russian-roulette rule as a value (see the header comment). The default is the field's
/// throughput rule from depth 3.
template <Scalar T, std::size_t N>
struct Roulette {
    RouletteRule rule = RouletteRule::throughput;  ///< Which rule decides the continuation probability.
    /// Band weights H (luminance by default, or 1/N each for the plain mean).
    Spectrum<T, N> weights = Spectrum<T, N>::default_luminance_weights();
    ThroughputNorm norm = ThroughputNorm::max;  ///< throughput: the norm of F a
    int min_depth = 3;                          ///< throughput: vertices before the first decision
    T cap = T(1);                               ///< throughput: the largest s, in (0, 1]
    T cutoff = T(0);                            ///< none: walks stop once max(F a) <= cutoff
    /// Szécsi 2009, §2.3: the incoming-radiance estimate L~ (zero: no offsets).
    Spectrum<T, N> estimate = Spectrum<T, N>(T(0));
    /// Szécsi 2009, §2.3: the estimate's goodness d in (0, 1]; with d < 1 walks continue with
    /// s_new = s d / (1 - (1 - d) s), which gives the roulette the same variance as s without
    /// the estimate, solving (1/s - 1) E[x^2] = (1/s_new - 1) E[(x - a L~)^2]. (Repaired: the
    /// extracted formula reads s / ((1 - s)/d + 1), which does not give s_new = s at d = 1.)
    T goodness = T(1);

    /// Szécsi 2009, §2.1's classic rule: s_i = <a_i, H>, the lobe albedo's H-weighted mean.
    static Roulette classic(const Spectrum<T, N>& H = Spectrum<T, N>::default_luminance_weights()) {
        return with_rule(RouletteRule::classic, H);
    }
    /// The classic rule on the plain mean of the bands.
    static Roulette mean() { return classic(Spectrum<T, N>(T(1) / T(N))); }
    /// Szécsi 2009, §2.2's spectral rule: s_i = sum F a_i H / sum F H, F the walk's throughput.
    static Roulette spectral(const Spectrum<T, N>& H = Spectrum<T, N>::default_luminance_weights()) {
        return with_rule(RouletteRule::spectral, H);
    }
    /// pbrt-v4 applies min(1, max band) from its second vertex on; Mitsuba 3 min(0.95, max
    /// band) from depth 5. After a continuation the throughput's norm is 1 again (F a / s), so
    /// the walk ends when the light it carries drops below what it started with.
    static Roulette throughput(ThroughputNorm norm = ThroughputNorm::max, int min_depth = 3, T cap = T(1),
                               const Spectrum<T, N>& H = Spectrum<T, N>::default_luminance_weights()) {
        Roulette r = with_rule(RouletteRule::throughput, H);
        r.norm = norm, r.min_depth = min_depth, r.cap = cap;
        return r;
    }
    /// No Russian roulette: with cutoff 0 only the tracer's depth cap ends walks, the reference
    /// for how much variance termination adds at all (which bounds what any L~ can gain); a
    /// positive cut-off is the biased "no roulette" baseline renderers offer.
    static Roulette none(T cutoff = T(0)) {
        Roulette r = with_rule(RouletteRule::none, Spectrum<T, N>::default_luminance_weights());
        r.cutoff = cutoff;
        return r;
    }

    /// Lobe share w_i >= 0 of a lobe of albedo a for a walk of throughput F (the rule's
    /// measure of F a, or of a alone for classic); lobes are selected in proportion to it.
    [[gnu::always_inline]] T selection_weight(const Spectrum<T, N>& F, const Spectrum<T, N>& a) const {
        switch (rule) {
            case RouletteRule::classic: return std::clamp(a.luminance(weights), T(0), T(1));
            case RouletteRule::spectral: return spectral_weight(F, a);
            case RouletteRule::throughput: {
                const Spectrum<T, N> Fa = F * a;
                const T v = norm == ThroughputNorm::max ? Fa.max() : Fa.luminance(weights);
                return v > T(0) ? v : T(0);  // NaN and negative throughputs select nothing
            }
            case RouletteRule::none: break;
        }
        return std::max((F * a).max(), T(0));
    }
    /// Probability s of continuing at a vertex of total albedo a, `depth` vertices after the
    /// camera, reduced by `goodness` when it is below 1 (Szécsi 2009, §2.3); callers clamp to [0, 1].
    [[gnu::always_inline]] T continuation(const Spectrum<T, N>& F, const Spectrum<T, N>& a, int depth) const {
        const T s = rule_continuation(F, a, depth);
        if (goodness == T(1)) return s;
        const T den = T(1) - (T(1) - goodness) * s;
        return den > T(0) ? s * goodness / den : s;
    }
    /// Radiance a terminated walk returns at a vertex of albedo a: a L~ (zero without an estimate).
    [[gnu::always_inline]] Spectrum<T, N> terminated(const Spectrum<T, N>& a) const { return a * estimate; }
    /// Offset a walk continued with probability s (> 0) adds: -(1 - s)/s a L~ (Szécsi 2009, §2.3).
    [[gnu::always_inline]] Spectrum<T, N> continued_offset(const Spectrum<T, N>& a, T s) const { return a * estimate * (-(T(1) - s) / s); }

private:
    static Roulette with_rule(RouletteRule rule, const Spectrum<T, N>& H) {
        Roulette r;
        r.rule = rule, r.weights = H;
        return r;
    }
    /// Szécsi 2009, §2.2: sum F a H / sum F H, so that the H-weighted throughput stays
    /// constant in expectation; zero when the walk carries nothing the lobe reflects.
    T spectral_weight(const Spectrum<T, N>& F, const Spectrum<T, N>& a) const {
        T num = 0, den = 0;
        for (std::size_t l = 0; l < N; ++l) {
            num += F[l] * a[l] * weights[l];
            den += F[l] * weights[l];
        }
        return den > T(0) ? std::clamp(num / den, T(0), T(1)) : T(0);
    }
    [[gnu::always_inline]] T rule_continuation(const Spectrum<T, N>& F, const Spectrum<T, N>& a, int depth) const {
        const T v = selection_weight(F, a);
        switch (rule) {
            case RouletteRule::throughput:
                if (depth < min_depth) return v > T(0) ? T(1) : T(0);
                return std::min(v, cap);
            case RouletteRule::none: return v > cutoff ? T(1) : T(0);
            default: return v;
        }
    }
};

static_assert(RoulettePolicy<Roulette<float, 3>, float, 3>);

/// The result of choosing among n lobes and termination with uniform `u`.
template <Scalar T, std::size_t N>
struct LobeSelection {
    std::array<T, max_brdf_lobes> probability{};  ///< s_i of the first `count` lobes; the rest zero
    std::size_t count = 0;  ///< Number of lobes considered (at most max_brdf_lobes).
    T total = 0;          ///< s = sum s_i (the continuation probability)
    int lobe = -1;        ///< selected lobe, -1 when the walk terminates
    Spectrum<T, N> offset{};  ///< the radiance estimate's term (zero without one)
    /// True when the walk stops here (no lobe selected).
    bool terminated() const { return lobe < 0; }
};

/// Selection probabilities s_i = s w_i / sum_j w_j, with w_i = roulette.selection_weight(F,
/// a_i) and s = roulette.continuation(F, sum a_i, depth) clamped to [0, 1]; the choice of a
/// lobe or termination by u in [0,1); the roulette's offset. `albedos` beyond max_brdf_lobes
/// are ignored (precondition: at most max_brdf_lobes).
template <Scalar T, std::size_t N, RoulettePolicy<T, N> R>
[[gnu::always_inline]] inline LobeSelection<T, N> select_lobe(const R& roulette, const Spectrum<T, N>& throughput,
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
    sel.offset = sel.lobe < 0 ? roulette.terminated(albedo) : roulette.continued_offset(albedo, sel.total);
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

/// The three combined-BRDF estimators of Szécsi 2009, §2.1.
enum class BrdfSelection { decomposition, weighted, mis };

/// Name used in benchmark output ("DIS", "W", "MIS").
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
    int lobe = -1;  ///< Index of the lobe sampled; -1: terminated
    Vec3<T> direction{0, 0, 1};  ///< Sampled incoming direction, unit, in the BRDF's local frame (z = normal)
    Spectrum<T, N> weight{};  ///< W_i / s_i, zero when terminated or the density is zero
    Spectrum<T, N> offset{};  ///< The roulette's radiance-estimate term, added whether or not the walk goes on
    /// True when the walk stops here.
    bool terminated() const { return lobe < 0; }
};

/// Russian roulette and lobe selection, then a direction from the chosen lobe and the weight of
/// the DIS, W or MIS estimator (`selection`). u_select and u_direction are independent
/// uniforms; `depth` counts the walk's scattering vertices before this one.
template <Scalar T, std::size_t N, MultiLobeBrdf<T, N> M, RoulettePolicy<T, N> R>
[[gnu::always_inline]] inline ScatterSample<T, N> scatter(const M& brdf, const R& roulette, const Spectrum<T, N>& throughput, T u_select,
                            const Vec2<T>& u_direction, int depth, BrdfSelection selection = BrdfSelection::mis) {
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
    T density = 0;  // of the estimator's sample: W_i / s_i = (what it weights) / density
    Spectrum<T, N> w(T(0));
    switch (selection) {
        case BrdfSelection::decomposition:
            density = T(brdf.pdf(i, out.direction)) * sel.probability[i];
            w = brdf.eval(i, out.direction);
            break;
        case BrdfSelection::weighted:
            for (std::size_t j = 0; j < n; ++j) w += brdf.eval(j, out.direction);
            density = T(brdf.pdf(i, out.direction)) * sel.total;
            break;
        case BrdfSelection::mis:
            for (std::size_t j = 0; j < n; ++j) {
                w += brdf.eval(j, out.direction);
                density += sel.probability[j] * T(brdf.pdf(j, out.direction));
            }
            break;
    }
    if (density > T(0)) out.weight = w / density;
    return out;
}

}  // namespace glint
