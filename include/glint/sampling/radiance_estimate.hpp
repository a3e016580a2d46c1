// glint/sampling/radiance_estimate.hpp: the incoming-radiance estimate L~ of the roulette with
// a radiance estimate (Szécsi 2009, §2.3; sampling/roulette.hpp's Roulette::estimate), from
// the scene (a closed scene's formula) or from pilot observations, and the estimate's goodness d
// (Roulette::goodness).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// Scene-wide incoming-radiance estimate of Szécsi 2009, §2.3, per band:
/// L~ = a~ Phi_e / (pi S (1 - a~)) from the emitted power Phi_e, the total surface area S and
/// the mean albedo a~ of a closed scene. Only reflected light is counted (not Phi_e itself),
/// which keeps it an underestimate as Szécsi 2009, §2.3 recommends.
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

/// One pilot observation for Szécsi 2009, §2.3: at a scattering point of albedo `albedo`, the
/// one-sample reflected-radiance estimate x = (w/p) L_in that a terminated walk would lose.
template <Scalar T, std::size_t N>
struct RoulettePilotSample {
    Spectrum<T, N> albedo{};     ///< Albedo a of the scattering point per band, in [0, 1].
    Spectrum<T, N> reflected{};  ///< Reflected-radiance estimate x = (w/p) L_in per band.
};

/// Szécsi 2009, §2.3 allows L~ to come "from the data gathered during a preprocessing phase".
/// Per band, the constant L~ that minimizes the added variance of termination,
/// sum (x - a L~)^2 over pilot samples, is L~ = sum x a / sum a^2 (least squares; clamped at
/// 0, since Szécsi 2009 asks for a non-negative estimate). Unlike the closed-scene formula above, it
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

/// Szécsi 2009, §2.3's goodness d = E[(x - a L~)^2] / E[x^2] of the estimate L~, in
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

}  // namespace glint
