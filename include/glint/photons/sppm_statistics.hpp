// glint/photons/sppm_statistics.hpp: a visible point's progressive statistics, the heart of
// progressive photon mapping (Hachisuka, Ogaki and Jensen 2008, §4.2) in its stochastic
// form (Hachisuka and Jensen 2009, §4.2): the radius R, the accumulated photon count N and
// the flux tau. After a photon pass that added M photons of BRDF-weighted flux phi inside R:
//   N' = N + alpha M,   R' = R sqrt(N' / (N + M)),   tau' = (tau + phi) R'^2 / R^2,
// so that the radius shrinks, each pass keeps the fraction alpha of its new photons, and the
// radiance estimate tau / (pi R^2 passes) (photon powers each a pass's flux share) converges:
// its bias vanishes as R -> 0 while the photon count inside R still grows (alpha in (0, 1);
// 2/3 is the papers' choice, and Knaus and Zwicker 2011 show it balances variance and bias).
#pragma once

#include <cmath>
#include <string>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// One visible point's progressive statistics (R^2, N, tau), updated once per photon pass.
struct SppmStatistics {
    double r2 = 0;    ///< R^2: the squared gather radius (scene units squared); start it at the initial radius squared.
    double n = 0;     ///< N: the accumulated (alpha-reduced) photon count.
    Rgb<double> tau{0.0};  ///< tau: the accumulated BRDF-weighted flux within R, per band.

    /// A pass that found m photons of summed BRDF-weighted power phi within R.
    void update(double m, const Rgb<double>& phi, double alpha) {
        if (m <= 0) return;
        const double n_new = n + alpha * m;
        const double r2_new = r2 * n_new / (n + m);
        tau = (tau + phi) * (r2_new / r2);
        n = n_new;
        r2 = r2_new;
    }
    /// Reflected radiance after `passes` passes.
    Rgb<double> radiance(int passes) const {
        return r2 > 0 && passes > 0 ? tau / (pi<double> * r2 * double(passes)) : Rgb<double>(0.0);
    }
};

/// Checks the reduction alpha is in (0, 1]; 1 keeps every photon (no radius reduction).
inline void check_sppm_alpha(double alpha) {
    if (!(alpha > 0.0 && alpha <= 1.0)) throw Error("SPPM alpha must be in (0, 1], got " + std::to_string(alpha));
}

}  // namespace glint
