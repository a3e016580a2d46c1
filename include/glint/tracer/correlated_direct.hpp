// glint/tracer/correlated_direct.hpp: CorrelatedDirect, Szécsi 2009, §3.2's multiple
// correlated sampling of polygon lights as a direct-lighting policy (tracer/lighting.hpp), with
// the per-pixel statistics of §3.1.1's lambda pooling; point lights get one shadow ray each.
//
// Per area light and vertex, K points uniform on the polygon: f = Le fr G V, main part
// g = Le fr~ G (V dropped, fr~ = kd / pi) with J from the point-to-polygon form factor
// (eq. 3.4). The combined estimate f/p + lambda (J - g/p) is linear in lambda: at the primary
// vertices its parts a = mean f/p and b = J - mean g/p are kept per sample instead of added to
// the walk, and finish() forms each pixel once with lambda = sum fg / sum gg over the pixel's
// (2r + 1)^2 neighbourhood. The pixel's mean and its variance (the variance layer) are those
// of the pooled estimator: the sample values X + a + lambda b (X the rest of the path) have,
// for the pooled lambda, mean and second moment from the per-pixel sums of X, a, b and their
// products.
//
// The weight's source (Szécsi 2009, §3.2, on setting the weight): lambda estimated from the
// samples (eq. 3.3, above), or "a more drastic approach", lambda = the fractional visibility, the
// share of the shadow rays (the samples with G > 0) that reach the light, pooled over the same
// neighbourhood; §3.2 reports the statistical lambda "slightly better" (bench_lambda measures
// both). Either lambda comes from the samples it weights, so either makes the combined
// estimate consistent, not unbiased (§3.1.1).
// finish() writes the film's "lambda" layer: each pixel's mean lambda (pooled, or of its
// primary vertices).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <utility>

#include <glint/core/spectrum.hpp>
#include <glint/sampling/correlated.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/lighting.hpp>

namespace glint {

/// Which estimator CorrelatedDirect returns (Szécsi 2009, §3.2): lambda = 0, lambda = 1, or
/// lambda estimated from the samples (eq. 3.3).
enum class DirectEstimator { importance, correlated, combined };

/// Where the combined estimator's lambda comes from (Szécsi 2009, §3.2):
/// eq. 3.3's statistical estimate, or the fractional visibility of the light samples.
enum class LambdaSource { statistical, visibility };

/// The direct-lighting policy of Szécsi 2009, §3.2 (see the header comment): K correlated
/// samples per area light and vertex, with per-pixel statistics that finish() turns into the
/// film's pooled estimate and its "lambda" layer. Read-only during rendering; the per-pixel
/// state lives in the renderer's pixel_state array.
template <Scalar T = float>
class CorrelatedDirect {
public:
    /// Per-band double-precision sums (pixel_state accumulates many samples).
    using D3 = Spectrum<double, 3>;

    /// The primary vertex's quantities of one pixel sample.
    struct vertex_record {
        /// Kept (pooled) part a = sum over the area lights of mean f/p, per band.
        Rgb<T> a{T(0)}, b{T(0)};
        /// \var b
        /// Kept (pooled) part b = sum over the area lights of (J - mean g/p), per band.

        /// Within-vertex co-moment of f/p and g/p, summed over the area lights (lambda's
        /// numerator).
        Rgb<T> fg{T(0)}, gg{T(0)};
        /// \var gg
        /// Within-vertex second moment of g/p about its mean, summed over the area lights
        /// (lambda's denominator).

        T lambda = std::numeric_limits<T>::quiet_NaN();  ///< mean per-vertex lambda over the lights
        /// Shadow rays that reached a light at this vertex.
        T visible = 0, traced = 0;
        /// \var traced
        /// Shadow rays traced at this vertex (those towards samples with G > 0).
    };
    /// Per-pixel sums over its samples (X: the sample's radiance without the kept parts).
    /// Samples with a non-finite X, a or b add to n but not to the per-band sums.
    struct pixel_state {
        /// Sum of X, per band.
        D3 x{0.0}, a{0.0}, b{0.0}, xx{0.0}, aa{0.0}, bb{0.0}, xa{0.0}, xb{0.0}, ab{0.0}, fg{0.0}, gg{0.0};
        /// \var a
        /// Sum of the records' a, per band.
        /// \var b
        /// Sum of the records' b, per band.
        /// \var xx
        /// Sum of X^2, per band.
        /// \var aa
        /// Sum of a^2, per band.
        /// \var bb
        /// Sum of b^2, per band.
        /// \var xa
        /// Sum of X a, per band.
        /// \var xb
        /// Sum of X b, per band.
        /// \var ab
        /// Sum of a b, per band.
        /// \var fg
        /// Sum of the records' fg co-moments, per band.
        /// \var gg
        /// Sum of the records' gg moments, per band.

        /// Sum of the samples' per-vertex lambdas (samples whose lambda is not NaN).
        double lambda_sum = 0, visible = 0, traced = 0;
        /// \var visible
        /// Shadow rays that reached a light, over the pixel's primary vertices.
        /// \var traced
        /// Shadow rays traced, over the pixel's primary vertices.

        /// Samples counted in lambda_sum.
        int lambda_count = 0, n = 0;
        /// \var n
        /// Pixel samples recorded.
    };

    /// The policy for `scene`'s area and point lights (copied), taking s.light_samples (clamped
    /// to 1 .. 64) samples per area light and vertex; pools lambda over
    /// s.lambda_filter_radius when the estimator is combined and the radius is >= 0.
    CorrelatedDirect(const Scene<T>& scene, const PathTracerSettings<T>& s, DirectEstimator estimator = DirectEstimator::combined,
                     LambdaSource source = LambdaSource::statistical)
        : lights_(scene), k_(std::size_t(std::clamp(s.light_samples, 1, 64))), estimator_(estimator), source_(source),
          radius_(s.lambda_filter_radius),
          pooled_(estimator == DirectEstimator::combined && s.lambda_filter_radius >= 0 && !lights_.empty()) {}

    /// The estimator fixed at construction.
    DirectEstimator estimator() const { return estimator_; }
    /// Where the combined estimator's lambda comes from.
    LambdaSource lambda_source() const { return source_; }

    /// Direct light at sp: point lights by one shadow ray each, every area light by K samples
    /// (K 2D numbers and up to K shadow rays per light). At a primary vertex with pooling,
    /// the area lights' a and b go into `rec` instead of the result.
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S& sampler, Q& queries, vertex_record* rec) const {
        Rgb<T> L = all_point_lights(std::span<const PointLight<T>>(lights_.point_lights()), sp, queries);
        if (lights_.empty()) return L;
        std::array<Vec2<T>, 64> u;
        T lambda_sum = 0;
        for (const auto& light : lights_.lights()) {
            for (std::size_t i = 0; i < k_; ++i) u[i] = sampler.get_2d();
            const std::span<const Vec2<T>> us(u.data(), k_);
            if (estimator_ == DirectEstimator::importance) {
                L += importance(sp, light, us, queries);
                continue;
            }
            T visible = 0, traced = 0;
            auto res = correlated_direct(
                light, sp.x, sp.n, [&](const Vec3<T>& wi) { return sp.brdf->f(sp.frame.to_local(wi)); },
                sp.brdf->kd() / pi<T>,
                [&](const Vec3<T>&, const Vec3<T>& y) {
                    const bool v = queries.visible(sp, light, y);
                    traced += T(1);
                    visible += v ? T(1) : T(0);
                    return v;
                },
                us);
            if (source_ == LambdaSource::visibility) {
                res.lambda = Rgb<T>(traced > T(0) ? visible / traced : T(0));
                for (std::size_t c = 0; c < 3; ++c) res.combined[c] = res.stats[c].estimate(res.main_part[c], res.lambda[c]);
            }
            if (rec) rec->visible += visible, rec->traced += traced;
            if (rec && pooled_) keep(*rec, res);
            else L += estimator_ == DirectEstimator::correlated ? res.correlated : res.combined;
            lambda_sum += res.lambda.mean();
        }
        if (rec) rec->lambda = lambda_sum / T(lights_.lights().size());
        return L;
    }

    /// Light samples estimate the area lights whole: emission the BRDF sample from a vertex
    /// whose lights were sampled meets counts 0.
    T emission_weight(const Arrival<T>& from, const Ray<T>&, const StoreHit<T>&) const {
        return from.lights_sampled ? T(0) : T(1);
    }

    /// Adds one pixel sample (primary record `rec`, radiance L without the kept parts) to the
    /// pixel's sums `st`.
    void record(pixel_state& st, const vertex_record& rec, const Rgb<T>& L) const {
        ++st.n;
        if (!std::isnan(rec.lambda)) {
            st.lambda_sum += double(rec.lambda);
            ++st.lambda_count;
        }
        st.visible += double(rec.visible), st.traced += double(rec.traced);
        // A non-finite sample counts as 0, as the renderer counts it.
        if (!(L.is_finite() && rec.a.is_finite() && rec.b.is_finite())) return;
        for (std::size_t c = 0; c < 3; ++c) {
            const double x = L[c], a = rec.a[c], b = rec.b[c];
            st.x[c] += x, st.a[c] += a, st.b[c] += b;
            st.xx[c] += x * x, st.aa[c] += a * a, st.bb[c] += b * b;
            st.xa[c] += x * a, st.xb[c] += x * b, st.ab[c] += a * b;
            st.fg[c] += rec.fg[c], st.gg[c] += rec.gg[c];
        }
    }

    /// The "lambda" layer; with pooling, each pixel's mean and variance of the pooled estimator.
    void finish(Film& film, std::span<const pixel_state> states) const {
        const int w = film.image.width, h = film.image.height;
        FilmLayer lambda{"lambda", Image<Rgb<float>>(w, h), true};
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const pixel_state& p = states[std::size_t(y) * std::size_t(w) + std::size_t(x)];
                float l = p.lambda_count ? float(p.lambda_sum / p.lambda_count) : 0.0f;
                if (pooled_) l = finish_pooled(film, x, y, p, pooled_lambda(states, w, h, x, y));
                lambda.pixels.at(x, y) = Rgb<float>(l);
            }
        film.layers.push_back(std::move(lambda));
    }

private:
    /// f/p alone (lambda = 0): no main part, so no form factor is computed.
    template <class Q>
        requires ShadowQueries<Q, T>
    Rgb<T> importance(const ShadingPoint<T>& sp, const PolygonLight<T, 3>& light, std::span<const Vec2<T>> u,
                      Q& queries) const {
        Rgb<T> L(T(0));
        const T area = light.sampler().area();
        for (const Vec2<T>& ui : u) {
            const Vec3<T> y = light.sampler().sample(ui);
            const T G = light.geometry(sp.x, sp.n, y) * area;
            if (G > T(0) && queries.visible(sp, light, y))
                L += light.radiance() * sp.brdf->f(sp.frame.to_local(safe_normalize(y - sp.x))) * (G / T(u.size()));
        }
        return L;
    }

    static void keep(vertex_record& rec, const CorrelatedResult<T, 3>& res) {
        for (std::size_t c = 0; c < 3; ++c) {
            rec.a[c] += res.importance[c];
            rec.b[c] += res.main_part[c] - res.stats[c].mean_g;
            rec.fg[c] += res.stats[c].comoment_fg;
            rec.gg[c] += res.stats[c].comoment_gg;
        }
    }

    /// lambda = sum fg / sum gg over the (2r + 1)^2 neighbourhood of (x, y), per band; or the
    /// neighbourhood's fractional visibility, sum visible / sum traced.
    D3 pooled_lambda(std::span<const pixel_state> states, int w, int h, int x, int y) const {
        D3 fg(0.0), gg(0.0), lambda(0.0);
        double visible = 0, traced = 0;
        for (int yy = std::max(0, y - radius_); yy <= std::min(h - 1, y + radius_); ++yy)
            for (int xx = std::max(0, x - radius_); xx <= std::min(w - 1, x + radius_); ++xx) {
                const pixel_state& q = states[std::size_t(yy) * std::size_t(w) + std::size_t(xx)];
                fg += q.fg;
                gg += q.gg;
                visible += q.visible, traced += q.traced;
            }
        if (source_ == LambdaSource::visibility) return D3(traced > 0.0 ? visible / traced : 0.0);
        for (std::size_t c = 0; c < 3; ++c) lambda[c] = gg[c] > 0.0 ? fg[c] / gg[c] : 0.0;
        return lambda;
    }

    /// The pixel's samples X + a + lambda b: mean and variance of the mean; returns lambda's
    /// mean over the bands.
    static float finish_pooled(Film& film, int x, int y, const pixel_state& p, const D3& lambda) {
        const double n = std::max(p.n, 1);
        for (std::size_t c = 0; c < 3; ++c) {
            const double l = lambda[c];
            const double s1 = p.x[c] + p.a[c] + l * p.b[c];
            const double s2 = p.xx[c] + p.aa[c] + l * l * p.bb[c] + 2.0 * (p.xa[c] + l * p.xb[c] + l * p.ab[c]);
            film.image.at(x, y)[c] = float(s1 / n);
            film.variance.at(x, y)[c] = n > 1 ? float(std::max(0.0, (s2 - s1 * s1 / n) / (n - 1.0) / n)) : 0.0f;
        }
        return float(lambda.mean());
    }

    SceneLights<T> lights_;
    std::size_t k_;
    DirectEstimator estimator_;
    LambdaSource source_;
    int radius_;
    bool pooled_;
};

}  // namespace glint
