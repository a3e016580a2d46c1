// glint/tracer/progressive.hpp: progressive rendering under a time budget. An integrator
// with passes (the path tracer's passes of spp samples per pixel, stochastic progressive
// photon mapping's passes of camera points and photons, the photon map's re-traced maps)
// renders pass after pass until the budget is spent or a pass count is reached, and its
// passes' images are averaged: what makes equal-time comparisons one command
// (glint-render --time-budget SECONDS: the path tracer's pass k renders samples k spp to
// (k + 1) spp - 1 of each pixel, so its passes are one render cut into pieces).
//
// A pass is a callable pass(k) -> RenderResult for k = 0, 1, ...; passes must be independent
// estimates (a different seed, or the next samples of one sequence: RenderSettings::
// first_sample), so that the mean image's variance is the sum of the passes' variances over
// K^2. The budget is checked between passes: a pass starts only if,
// as long as the mean pass so far, it ends within the budget (the first always runs, and a
// slower pass may still end after it); the result says how long the passes took.
#pragma once

#include <chrono>
#include <cmath>
#include <concepts>
#include <string>
#include <type_traits>

#include <glint/core/error.hpp>
#include <glint/core/image.hpp>
#include <glint/tracer/renderer.hpp>

namespace glint {

/// When passes stop: after `seconds` (0: no budget) or after `passes` (0: no cap); at least
/// one of the two must be set. At least one pass always runs.
struct PassBudget {
    double seconds = 0;  ///< Wall-clock budget in seconds, >= 0 and finite; 0: none.
    int passes = 0;      ///< Pass cap, >= 0; 0: none.

    /// Throws glint::Error for a negative or non-finite budget, a negative pass count, or
    /// neither limit set.
    void validate() const {
        if (!(seconds >= 0) || !std::isfinite(seconds))
            throw Error("time budget must be a finite number of seconds >= 0, got " + std::to_string(seconds));
        if (passes < 0) throw Error("pass count must be >= 0, got " + std::to_string(passes));
        if (seconds == 0 && passes == 0) throw Error("a progressive render needs a time budget or a pass count");
    }
    /// Whether to stop after `done` passes that took `elapsed` seconds: at the pass count, or
    /// when one more pass, as long as the mean pass so far, would end after the budget.
    bool stop(int done, double elapsed) const {
        return (passes > 0 && done >= passes) || (seconds > 0 && elapsed * double(done + 1) / double(done) > seconds);
    }
};

/// The mean of a progressive render's passes, their summed statistics and how many ran.
struct ProgressiveResult : RenderResult {
    int passes = 0;  ///< Passes that ran and were averaged, >= 1 after a render.
};

namespace detail {

/// Adds pass image `b` into the running mean `a` of k earlier passes (and the variances: the
/// mean's variance is the sum of the passes' over (k + 1)^2).
inline void fold_pass(Film& a, const Film& b, int k) {
    const float wa = float(k) / float(k + 1), wb = 1.0f / float(k + 1);
    for (std::size_t i = 0; i < a.image.pixels.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            a.image.pixels[i][c] = a.image.pixels[i][c] * wa + b.image.pixels[i][c] * wb;
            a.variance.pixels[i][c] = a.variance.pixels[i][c] * wa * wa + b.variance.pixels[i][c] * wb * wb;
        }
}

}  // namespace detail

/// Runs pass(0), pass(1), ... until `budget` says stop; returns the passes' mean image (the
/// first pass's layers) with the statistics summed and seconds measured around the loop.
template <class Pass>
    requires std::convertible_to<std::invoke_result_t<Pass&, int>, RenderResult>
ProgressiveResult render_passes(const PassBudget& budget, Pass&& pass) {
    budget.validate();
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    ProgressiveResult out;
    for (int k = 0;; ++k) {
        const RenderResult r = pass(k);
        if (k == 0) {
            static_cast<RenderResult&>(out) = r;
        } else {
            detail::fold_pass(out, r, k);
            out.rays += r.rays;
            out.paths += r.paths;
            out.capped_walks += r.capped_walks;
        }
        out.passes = k + 1;
        if (budget.stop(out.passes, std::chrono::duration<double>(clock::now() - start).count())) break;
    }
    out.seconds = std::chrono::duration<double>(clock::now() - start).count();
    return out;
}

}  // namespace glint
