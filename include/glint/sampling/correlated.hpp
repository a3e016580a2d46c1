// glint/sampling/correlated.hpp: multiple correlated sampling, the combination of correlated
// sampling (a main part g with known integral J) and importance sampling (density p).
//
// Szécsi 2009, §3.1: from each sample u ~ p the combined primary estimator is
//   I^ = f/p + lambda (J - g/p)
// (lambda = 0: importance sampling, lambda = 1: correlated sampling). The variance-optimal
//   lambda = E[(J - g/p)(I - f/p)] / E[(J - g/p)^2]                     (eq. 3.2)
// is estimated from the M samples (eq. 3.3, whose sums and 1/M were scattered by the extraction:
// repaired to  sum_i (J - g_i/p_i)(mean_j f_j/p_j - f_i/p_i) / sum_j (J - g_j/p_j)^2 ).
// The numerator is exactly the centred co-moment sum_i (f_i - f_mean)(g_i - g_mean) (expand it:
// the J terms cancel), the denominator is centred on J, the known mean of g/p.
// LambdaEstimate::eq33 is that literal form. LambdaEstimate::regression (the default) centres
// the denominator on the sample mean too: the least-squares control-variate coefficient, the
// same quantity (E[g/p] = J) estimated with lower variance, and with the property Szécsi 2009
// claims for a fully visible diffuse light -- f = g gives lambda = 1 exactly and I^ = J with zero variance
// (with eq33, lambda = 1 - O(1/M) and I^ carries a residual O(M^-1.5) error).
// lambda estimated from the same samples makes I^ consistent, not unbiased;
// filter_lambda pools the statistics of neighbouring pixels (section 3.1.1)
// and a fixed or independently estimated lambda makes it unbiased.
//
// Szécsi 2009, §3.2: direct illumination from a polygon light: f = Le fr nu G,
// main part g = Le~ fr~ G with the visibility nu dropped, and J = Le~ fr~ integral_L G dy given in
// closed form by the point-to-polygon form factor (eq. 3.4):
//   integral_L G(x, y) dy = 1/2 sum_l angle(R_l, R_l+1) (R_l x R_l+1)/|R_l x R_l+1| . n_x
// (repaired: the extraction lost the angle symbol and the sign convention; we use the unsigned
// angle in [0, pi] between R_l and R_l+1 with the direction of R_l x R_l+1 and take the absolute
// value of the sum, so either winding works. The polygon is first clipped to the half-space in
// front of x, matching G with cos(theta'_x) clamped at zero). The point-to-polygon form factor is
// this integral divided by pi.
//
// Szécsi 2009, §3.3: environment lighting over a decomposition of the sphere of
// directions into cells Omega_d, each estimated by the combined estimator with one of two main
// parts that neglect visibility:
//   eq. 3.5  g1(w) = L_env(w) a_d / |Omega_d|,  a_d = integral_{Omega_d} fr cos  (the BRDF*cos
//            replaced by its cell average),
//   eq. 3.6  g2(w) = L~_d fr(w) cos(theta),   L~_d = integral_{Omega_d} L_env / |Omega_d|
//            (the radiance replaced by its cell average),
// both with J = L~_d a_d. (Repaired: the extraction writes L~_d as the bare integral and g1
// without 1/|Omega_d|; with either literal reading the two J's differ by |Omega_d|. The text calls
// L~_d "the average over the solid angle", which fixes the normalization used here.)
// Section 3.3.1: equal-solid-angle cells from uniform phi intervals and cos(theta) intervals
// (theta_j = arccos of uniformly spaced values); |Omega_d| = (phi_i+1 - phi_i)(cos theta_j -
// cos theta_j+1), and for a diffuse BRDF a_d = fr (phi_i+1 - phi_i)(cos^2 theta_j -
// cos^2 theta_j+1)/2 (the extraction has both differences with the opposite sign, which would
// make them negative for theta_j < theta_j+1; repaired).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <type_traits>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/sampling/warps.hpp>

namespace glint {

/// How lambda is estimated from the samples (see the header comment).
enum class LambdaEstimate { regression, eq33 };

/// Running statistics of the pairs (f/p, g/p) of one integral: means and centred co-moments
/// (Welford updates, so f == g gives bitwise-equal co-moments and lambda == 1 exactly).
template <Scalar T>
struct CorrelatedStats {
    T n = 0;  ///< Number of samples added (a count held in T; 0 before the first add()).
    /// Sample mean of f/p (0 before the first add()).
    T mean_f = 0, mean_g = 0;  ///< Sample mean of g/p (0 before the first add()).
    /// Centred co-moment sum (f - mean_f)(g - mean_g) over the samples.
    T comoment_fg = 0, comoment_gg = 0;  ///< Centred second moment sum (g - mean_g)^2 over the samples.

    /// Add one sample: f_over_p = f(u)/p(u), g_over_p = g(u)/p(u).
    void add(T f_over_p, T g_over_p) {
        n += T(1);
        const T df = f_over_p - mean_f, dg = g_over_p - mean_g;
        mean_f += df / n;
        mean_g += dg / n;
        const T eg = g_over_p - mean_g;
        comoment_fg += df * eg;
        comoment_gg += dg * eg;
    }

    /// Denominator of lambda: sum (g_i - c)^2 with c = mean_g (regression) or J (eq33).
    T lambda_denominator(T J, LambdaEstimate form) const {
        if (form == LambdaEstimate::regression) return comoment_gg;
        return comoment_gg + n * (J - mean_g) * (J - mean_g);
    }

    /// Estimated optimal weight (0 when the main part does not vary over the samples).
    T lambda(T J, LambdaEstimate form = LambdaEstimate::regression) const {
        const T den = lambda_denominator(J, form);
        return den > T(0) ? comoment_fg / den : T(0);
    }

    /// Combined estimate of the integral for a given weight.
    T estimate(T J, T weight) const { return mean_f + weight * (J - mean_g); }
    /// Combined estimate with lambda estimated from these samples.
    T estimate(T J, LambdaEstimate form = LambdaEstimate::regression) const {
        return estimate(J, lambda(J, form));
    }
    /// Importance-sampling estimate (lambda = 0): the mean of f/p.
    T importance_estimate() const { return mean_f; }
    /// Correlated-sampling estimate (lambda = 1) for the main part's known integral J.
    T correlated_estimate(T J) const { return estimate(J, T(1)); }
};

/// The combined estimate of one integral without section 3.1.1's initial bias, from the M
/// samples' f_i/p_i and g_i/p_i: sample i is weighted by lambda_-i, estimated (regression form)
/// from the other M - 1 samples and clamped to [0, 1] (the convex combination of correlated and
/// importance sampling that section 3.1 introduces lambda as). lambda_-i is independent of
/// sample i, so E[f_i/p_i + lambda_-i (J - g_i/p_i)] = I exactly, whatever the lambda's noise:
///   I^ = 1/M sum_i [f_i/p_i + lambda_-i (J - g_i/p_i)]
/// (Szécsi 2009, §3.1.1 reduces the bias instead by pooling lambda over neighbouring pixels.)
/// Raw sums in double; M < 3 leaves no variance to estimate lambda_-i from: importance sampling.
template <Scalar T>
T leave_one_out_estimate(std::span<const T> f_over_p, std::span<const T> g_over_p, T J) {
    const std::size_t m = std::min(f_over_p.size(), g_over_p.size());
    double sf = 0, sg = 0, sfg = 0, sgg = 0;
    for (std::size_t i = 0; i < m; ++i) {
        const double f = f_over_p[i], g = g_over_p[i];
        sf += f, sg += g, sfg += f * g, sgg += g * g;
    }
    if (m == 0) return T(0);
    double sum = 0;
    const double rest = double(m) - 1.0;
    for (std::size_t i = 0; i < m; ++i) {
        const double f = f_over_p[i], g = g_over_p[i];
        double lambda = 0;
        if (m >= 3) {
            const double rf = sf - f, rg = sg - g;
            const double cgg = (sgg - g * g) - rg * rg / rest, cfg = (sfg - f * g) - rf * rg / rest;
            if (cgg > (sgg - g * g) * 0x1p-40) lambda = std::clamp(cfg / cgg, 0.0, 1.0);
        }
        sum += f + lambda * (double(J) - g);
    }
    return T(sum / double(m));
}

/// Section 3.1.1: lambda of each pixel from the statistics pooled over the (2 radius + 1)^2
/// neighbourhood (clamped at the image border). Within-pixel co-moments are summed, so pixels
/// with different means do not distort each other's correlation. Writes width*height weights.
template <Scalar T>
void filter_lambda(std::span<const CorrelatedStats<T>> stats, std::span<const T> J, int width,
                   int height, int radius, std::span<T> lambda_out,
                   LambdaEstimate form = LambdaEstimate::regression) {
    const auto count = std::size_t(std::max(width, 0)) * std::size_t(std::max(height, 0));
    if (width <= 0 || height <= 0 || radius < 0 || stats.size() != count || J.size() != count ||
        lambda_out.size() != count)
        throw Error("glint::filter_lambda: expected " + std::to_string(width) + "x" +
                    std::to_string(height) + " statistics, J values and outputs and radius >= 0, got " +
                    std::to_string(stats.size()) + ", " + std::to_string(J.size()) + ", " +
                    std::to_string(lambda_out.size()) + " and radius " + std::to_string(radius));
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            T num = 0, den = 0;
            for (int yy = std::max(0, y - radius); yy <= std::min(height - 1, y + radius); ++yy) {
                for (int xx = std::max(0, x - radius); xx <= std::min(width - 1, x + radius); ++xx) {
                    const std::size_t k = std::size_t(yy) * std::size_t(width) + std::size_t(xx);
                    num += stats[k].comoment_fg;
                    den += stats[k].lambda_denominator(J[k], form);
                }
            }
            lambda_out[std::size_t(y) * std::size_t(width) + std::size_t(x)] = den > T(0) ? num / den : T(0);
        }
    }
}

/// Most vertices a polygon light may have (clipping works on the stack).
inline constexpr std::size_t max_polygon_vertices = 32;

namespace detail {

/// Clip the polygon (relative vectors R_l = v_l - x) to the half-space dot(R, n) >= 0.
/// Returns the vertex count of the result (at most in + 1 <= max_polygon_vertices + 1).
template <Scalar T>
std::size_t clip_to_hemisphere(std::span<const Vec3<T>> in, const Vec3<T>& n,
                               std::array<Vec3<T>, max_polygon_vertices + 1>& out) {
    std::size_t k = 0;
    const std::size_t m = in.size();
    for (std::size_t i = 0; i < m; ++i) {
        const Vec3<T>& a = in[i];
        const Vec3<T>& b = in[(i + 1) % m];
        const T da = glm::dot(a, n), db = glm::dot(b, n);
        if (da >= T(0)) out[k++] = a;
        if ((da >= T(0)) != (db >= T(0))) {
            const T t = da / (da - db);
            out[k++] = a + t * (b - a);
        }
        if (k > max_polygon_vertices) break;
    }
    return k;
}

/// atan2(y, x) for y >= 0, the unsigned angle of eq. 3.4. Double: std::atan2. Float: one
/// division t = min(y, |x|) / max(y, |x|) in [0, 1], atan t = t P(t^2) with P of degree 7 (a
/// minimax fit, |error| <= 1.2e-7 rad in float arithmetic, a tenth of what the form factor's
/// float tests allow), then the reflections pi/2 - a and pi - a as selects, not branches.
/// libm's atan2f cost 4-5 times as many instructions and, with the branches of a range
/// reduction on data-dependent angles, made the form factor most of the combined estimator's
/// time overhead (callgrind and timings on arealight).
template <Scalar T>
T unsigned_angle(T y, T x) {
    if constexpr (!std::is_same_v<T, float>) {
        return std::atan2(y, x);
    } else {
        const float ax = std::abs(x);
        const float hi = std::max(y, ax), lo = std::min(y, ax);
        const float t = hi > 0.0f ? lo / hi : 0.0f;
        const float z = t * t;
        float p = -4.054559395e-03f;
        p = p * z + 2.186292969e-02f;
        p = p * z - 5.591228977e-02f;
        p = p * z + 9.642194957e-02f;
        p = p * z - 1.390862912e-01f;
        p = p * z + 1.994656473e-01f;
        p = p * z - 3.332985938e-01f;
        p = p * z + 9.999993443e-01f;
        float a = t * p;
        a = y > ax ? pi<float> / 2.0f - a : a;
        return x < 0.0f ? pi<float> - a : a;
    }
}

}  // namespace detail

/// Eq. 3.4: integral over the polygon of G(x, y) = cos(theta'_x) cos(theta_y) / |x - y|^2
/// for a receiver at x with unit normal n (the polygon's own orientation is ignored; cos
/// theta'_x is clamped at zero by clipping). At most max_polygon_vertices vertices.
/// Per edge (a, b) = (R_l, R_l+1): angle(a, b) = atan2(|a x b|, a . b) and the unit normal
/// (a x b) / |a x b|, so a x b is computed once and nothing is normalized twice; the polygon
/// is copied and clipped only when a vertex lies behind the tangent plane of x.
template <Scalar T>
T polygon_geometry_integral(const Vec3<T>& x, const Vec3<T>& n, std::span<const Vec3<T>> vertices) {
    std::array<Vec3<T>, max_polygon_vertices> rel;
    const std::size_t m = std::min(vertices.size(), max_polygon_vertices);
    bool in_front = true;
    for (std::size_t i = 0; i < m; ++i) {
        rel[i] = vertices[i] - x;
        in_front = in_front && glm::dot(rel[i], n) >= T(0);
    }
    std::array<Vec3<T>, max_polygon_vertices + 1> clipped;
    const Vec3<T>* poly = rel.data();
    std::size_t k = m;
    if (!in_front) {
        k = detail::clip_to_hemisphere(std::span<const Vec3<T>>(rel.data(), m), n, clipped);
        poly = clipped.data();
    }
    if (k < 3) return T(0);
    T sum = 0;
    for (std::size_t l = 0; l < k; ++l) {
        const Vec3<T>& a = poly[l];
        const Vec3<T>& b = poly[l + 1 == k ? 0 : l + 1];
        const Vec3<T> c = glm::cross(a, b);
        const T len = std::sqrt(glm::dot(c, c));
        if (!(len > T(0))) continue;  // collinear with x: no contribution
        sum += detail::unsigned_angle(len, glm::dot(a, b)) * (glm::dot(c, n) / len);
    }
    return std::abs(sum) / T(2);
}

/// Point-to-polygon form factor (eq. 3.4 divided by pi).
template <Scalar T>
T point_to_polygon_form_factor(const Vec3<T>& x, const Vec3<T>& n, std::span<const Vec3<T>> vertices) {
    return polygon_geometry_integral(x, n, vertices) / pi<T>;
}

/// Which sides of a polygon light emit. `front`: the side its vertex order is
/// counter-clockwise from (the side PolygonSampler::normal points to), as the tracer's area
/// lights; a receiver behind it gets nothing, so the winding decides what is lit. `both`: either
/// side emits Le, so either winding gives the same light.
enum class LightSides { front, both };

/// A planar convex polygon emitting constant radiance Le from the sides `sides` names.
template <Scalar T, std::size_t N>
class PolygonLight {
public:
    /// A light over `vertices` (planar, convex, in order, world space) emitting `radiance` (Le per
    /// band) from `sides`. Throws Error for more than max_polygon_vertices vertices, fewer than
    /// 3 or a degenerate polygon (PolygonSampler).
    PolygonLight(std::span<const Vec3<T>> vertices, const Spectrum<T, N>& radiance,
                 LightSides sides = LightSides::front)
        : sampler_(vertices), radiance_(radiance), sides_(sides) {
        if (vertices.size() > max_polygon_vertices)
            throw Error("glint::PolygonLight: at most " + std::to_string(max_polygon_vertices) +
                        " vertices, got " + std::to_string(vertices.size()));
    }
    /// The polygon and its uniform-area sampler (vertices, normal, area).
    const PolygonSampler<T>& sampler() const { return sampler_; }
    /// The emitted radiance Le, constant over the polygon.
    const Spectrum<T, N>& radiance() const { return radiance_; }
    /// Which sides emit.
    LightSides sides() const { return sides_; }

    /// Integral of G over the light for a receiver at x with normal n (zero when x is behind a
    /// front-only light).
    T geometry_integral(const Vec3<T>& x, const Vec3<T>& n) const {
        if (sides_ == LightSides::front && glm::dot(x - sampler_.vertices()[0], sampler_.normal()) <= T(0)) return T(0);
        return polygon_geometry_integral(x, n, sampler_.vertices());
    }

    /// G(x, y) with both cosines clamped at zero (the light's cosine taken on its emitting side).
    T geometry(const Vec3<T>& x, const Vec3<T>& n, const Vec3<T>& y) const {
        const Vec3<T> d = y - x;
        const T r2 = glm::dot(d, d);
        if (!(r2 > T(0))) return T(0);
        const T cos_x = glm::dot(d, n), dn = -glm::dot(d, sampler_.normal());
        const T cos_y = sides_ == LightSides::both ? std::abs(dn) : dn;
        if (cos_x <= T(0) || cos_y <= T(0)) return T(0);
        return cos_x * cos_y / (r2 * r2);
    }

private:
    PolygonSampler<T> sampler_;
    Spectrum<T, N> radiance_;
    LightSides sides_;
};

/// The three estimates of one integral and the per-band statistics they came from.
template <Scalar T, std::size_t N>
struct CorrelatedResult {
    Spectrum<T, N> combined{};     ///< f/p + lambda (J - g/p), lambda from the samples
    Spectrum<T, N> importance{};   ///< Importance-sampling estimate (lambda = 0)
    Spectrum<T, N> correlated{};   ///< Correlated-sampling estimate (lambda = 1)
    Spectrum<T, N> main_part{};    ///< J, the main part's integral in closed form
    Spectrum<T, N> lambda{};       ///< per band (direct lighting); mean over cells (environment)
    std::array<CorrelatedStats<T>, N> stats{};  ///< direct lighting only, for filter_lambda; zero for environment lighting
};

/// Direct illumination of x (normal n, outgoing direction fixed inside `brdf`) by a polygon
/// light with the combined estimator, one light sample per uniform pair in `uniforms` (points
/// uniform in area, p = 1/area). brdf(wi) returns fr for the unit direction wi towards the light;
/// brdf_approx is fr~, the constant main-part BRDF (fr itself for a diffuse receiver);
/// visible(x, y) is the visibility nu. No allocation.
template <Scalar T, std::size_t N, class Brdf, class Visibility>
CorrelatedResult<T, N> correlated_direct(const PolygonLight<T, N>& light, const Vec3<T>& x,
                                         const Vec3<T>& n, Brdf&& brdf,
                                         const Spectrum<T, N>& brdf_approx, Visibility&& visible,
                                         std::span<const Vec2<T>> uniforms,
                                         LambdaEstimate form = LambdaEstimate::regression) {
    CorrelatedResult<T, N> out;
    const T area = light.sampler().area();
    // One pass of raw sums per band, in double: sum f, g, fg, gg (f, g = f/p, g/p). For float
    // samples the products are exact in double, and the co-moments sum fg - sum f sum g / M
    // lose to cancellation only the relative variance of g, far above double's precision.
    // (A two-pass or Welford update costs a division or a second loop per band.)
    // f and g come from the same expression, and every sum and co-moment of f is formed
    // exactly as that of g: f == g (a fully visible light with fr = fr~) gives bitwise-equal
    // co-moments, so lambda == 1 exactly; f == 0 (fully occluded) gives lambda == 0 exactly.
    std::array<double, N> sf{}, sg{}, sfg{}, sgg{};
    auto add = [](double& sum, double a, double b) { sum += a * b; };
    for (const Vec2<T>& u : uniforms) {
        const Vec3<T> y = light.sampler().sample(u);
        const T G = light.geometry(x, n, y) * area;  // G / p
        if (!(G > T(0))) continue;                   // f = g = 0: adds nothing to any sum
        const Spectrum<T, N> g = light.radiance() * brdf_approx * G;
        Spectrum<T, N> f(T(0));
        if (visible(x, y)) f = light.radiance() * brdf(safe_normalize(y - x)) * G;
        for (std::size_t l = 0; l < N; ++l) {
            sf[l] += double(f[l]);
            sg[l] += double(g[l]);
            add(sfg[l], double(f[l]), double(g[l]));
            add(sgg[l], double(g[l]), double(g[l]));
        }
    }
    // J after the samples: the shadow rays start without waiting for the form factor's
    // divisions and square roots.
    out.main_part = light.radiance() * brdf_approx * light.geometry_integral(x, n);
    const double M = double(uniforms.size());
    for (std::size_t l = 0; l < N; ++l) {
        CorrelatedStats<T>& st = out.stats[l];
        const T J = out.main_part[l];
        if (M > 0) {
            st.n = T(M);
            st.mean_f = T(sf[l] / M);
            st.mean_g = T(sg[l] / M);
            st.comoment_fg = T(sfg[l] - sf[l] * sg[l] / M);
            st.comoment_gg = T(sgg[l] - sg[l] * sg[l] / M);
            // Rounding residue of a constant g (no variance to measure): lambda is moot there
            // (g/p = J), so no lambda is estimated from it.
            if (!(st.comoment_gg > T(sgg[l] * 0x1p-40))) st.comoment_fg = st.comoment_gg = T(0);
        }
        out.lambda[l] = st.lambda(J, form);
        out.combined[l] = st.estimate(J, out.lambda[l]);
        out.importance[l] = st.importance_estimate();
        out.correlated[l] = st.correlated_estimate(J);
    }
    return out;
}

/// Section 3.3.1: n_phi x n_theta cells of equal solid angle over the hemisphere about +z (or
/// the whole sphere): uniform phi intervals, cos(theta) boundaries uniformly spaced.
template <Scalar T>
class SphereCells {
public:
    /// n_phi azimuth intervals times n_theta cos(theta) intervals over the hemisphere z >= 0, or
    /// the whole sphere when `hemisphere` is false. Throws Error unless both counts are positive.
    SphereCells(int n_phi, int n_theta, bool hemisphere = true)
        : n_phi_(n_phi), n_theta_(n_theta), hemisphere_(hemisphere) {
        if (n_phi <= 0 || n_theta <= 0)
            throw Error("glint::SphereCells: need positive cell counts, got " +
                        std::to_string(n_phi) + " x " + std::to_string(n_theta));
    }
    /// Number of cells, n_phi * n_theta; cells are indexed d = j * n_phi + i.
    std::size_t count() const { return std::size_t(n_phi_) * std::size_t(n_theta_); }
    /// cos(theta_j), j = 0 .. n_theta (from 1 down to 0, or -1 for the sphere).
    T cos_boundary(int j) const {
        return T(1) - (hemisphere_ ? T(1) : T(2)) * T(j) / T(n_theta_);
    }
    /// phi_i = 2 pi i / n_phi in radians, i = 0 .. n_phi.
    T phi_boundary(int i) const { return T(2) * pi<T> * T(i) / T(n_phi_); }
    /// |Omega_d| = (phi_i+1 - phi_i)(cos theta_j - cos theta_j+1), the same for every cell.
    T solid_angle() const {
        return (T(2) * pi<T> / T(n_phi_)) * ((hemisphere_ ? T(1) : T(2)) / T(n_theta_));
    }
    /// Uniform direction in cell d = j * n_phi + i (density 1 / solid_angle()).
    Vec3<T> sample(std::size_t d, const Vec2<T>& u) const {
        const int i = int(d % std::size_t(n_phi_)), j = int(d / std::size_t(n_phi_));
        const T c0 = cos_boundary(j), c1 = cos_boundary(j + 1);
        const T z = c0 + (c1 - c0) * u.y;
        const T r = std::sqrt(std::max(T(0), T(1) - z * z));
        const T phi = phi_boundary(i) + (phi_boundary(i + 1) - phi_boundary(i)) * u.x;
        return Vec3<T>(r * std::cos(phi), r * std::sin(phi), z);
    }
    /// Section 3.3.1's closed form divided by fr: integral over cell d of max(cos theta, 0),
    /// = (phi_i+1 - phi_i)(cos^2 theta_j - cos^2 theta_j+1)/2 above the horizon.
    T cosine_integral(std::size_t d) const {
        const int j = int(d / std::size_t(n_phi_));
        const T c0 = std::max(cos_boundary(j), T(0)), c1 = std::max(cos_boundary(j + 1), T(0));
        return (T(2) * pi<T> / T(n_phi_)) * (c0 * c0 - c1 * c1) / T(2);
    }
    /// The cell d = j * n_phi + i that holds the unit direction w (the inverse of sample()).
    std::size_t cell_of(const Vec3<T>& w) const {
        const T span = hemisphere_ ? T(1) : T(2);
        const int j = std::clamp(int((T(1) - w.z) / span * T(n_theta_)), 0, n_theta_ - 1);
        T phi = std::atan2(w.y, w.x);
        if (phi < T(0)) phi += T(2) * pi<T>;
        const int i = std::clamp(int(phi / (T(2) * pi<T>) * T(n_phi_)), 0, n_phi_ - 1);
        return std::size_t(j) * std::size_t(n_phi_) + std::size_t(i);
    }
    /// V_d = integral over cell d of w dw, in closed form: with s(z) = sqrt(1 - z^2) and
    /// S = integral of s dz over the cell's cos(theta) interval, V_d = ((sin phi_i+1 - sin phi_i) S,
    /// (cos phi_i - cos phi_i+1) S, (phi_i+1 - phi_i)(cos^2 theta_j - cos^2 theta_j+1)/2).
    /// n . V_d is the integral of cos(n, w) over the cell, the exact a_d of a diffuse BRDF with
    /// normal n where the whole cell lies above the tangent plane (min_cosine(d, n) >= 0); the
    /// section 3.3.1 closed form is its n = +z case.
    Vec3<T> direction_integral(std::size_t d) const {
        const int i = int(d % std::size_t(n_phi_)), j = int(d / std::size_t(n_phi_));
        const T c0 = cos_boundary(j), c1 = cos_boundary(j + 1);
        auto antiderivative = [](T z) { return (z * std::sqrt(std::max(T(0), T(1) - z * z)) + std::asin(z)) / T(2); };
        const T S = antiderivative(c0) - antiderivative(c1);
        const T p0 = phi_boundary(i), p1 = phi_boundary(i + 1);
        return Vec3<T>((std::sin(p1) - std::sin(p0)) * S, (std::cos(p0) - std::cos(p1)) * S,
                       (p1 - p0) * (c0 * c0 - c1 * c1) / T(2));
    }
    /// A cell's extent: unit vectors of its azimuth boundaries phi_i, phi_i+1 in the xy plane,
    /// phi_i+1 - phi_i, and its cos(theta) interval [z_lo, z_hi].
    struct Bounds {
        /// Unit xy vector (cos phi_i, sin phi_i) of the lower azimuth boundary.
        Vec2<T> e0, e1;  ///< Unit xy vector (cos phi_i+1, sin phi_i+1) of the upper azimuth boundary.
        /// \var z_lo
        /// Lower end cos(theta_j+1) of the cell's cos(theta) interval.

        /// Azimuth width phi_i+1 - phi_i in radians.
        T width, z_lo, z_hi;  ///< Upper end cos(theta_j) of the cell's cos(theta) interval.
    };
    /// The extent of cell d (d < count()), for min_cosine().
    Bounds bounds(std::size_t d) const {
        const int i = int(d % std::size_t(n_phi_)), j = int(d / std::size_t(n_phi_));
        const T p0 = phi_boundary(i), p1 = phi_boundary(i + 1);
        return {Vec2<T>(std::cos(p0), std::sin(p0)), Vec2<T>(std::cos(p1), std::sin(p1)), p1 - p0,
                cos_boundary(j + 1), cos_boundary(j)};
    }
    /// The least n . w over the directions w of a cell (n a unit vector), exactly:
    /// n . w = n_z z + sqrt(1 - z^2) (n_xy . e(phi)); its least value over the cell's azimuths is
    /// A = -|n_xy| when the azimuth of -n_xy lies in the cell, else the smaller of n_xy . e0 and
    /// n_xy . e1; and n_z z + A sqrt(1 - z^2) is least at an end of the z interval or, for A < 0,
    /// at z* = -n_z / sqrt(n_z^2 + A^2), where it is -sqrt(n_z^2 + A^2). No trigonometry.
    static T min_cosine(const Bounds& b, const Vec3<T>& n) {
        auto cross = [](const Vec2<T>& u, const Vec2<T>& v) { return u.x * v.y - u.y * v.x; };
        const Vec2<T> a(-n.x, -n.y);  // the azimuth where n_xy . e(phi) is least
        const bool inside = b.width < pi<T> ? cross(b.e0, a) >= T(0) && cross(a, b.e1) >= T(0)
                                            : !(cross(b.e1, a) > T(0) && cross(a, b.e0) > T(0));
        const T A = inside ? -std::sqrt(a.x * a.x + a.y * a.y)
                           : std::min(n.x * b.e0.x + n.y * b.e0.y, n.x * b.e1.x + n.y * b.e1.y);
        auto h = [&](T z) { return n.z * z + A * std::sqrt(std::max(T(0), T(1) - z * z)); };
        T least = std::min(h(b.z_lo), h(b.z_hi));
        const T len = std::sqrt(n.z * n.z + A * A);
        if (A < T(0) && len > T(0)) {
            const T z_star = -n.z / len;
            if (z_star >= b.z_lo && z_star <= b.z_hi) least = std::min(least, -len);
        }
        return least;
    }
    /// The least n . w over the directions w of cell d (n a unit vector); negative when part of
    /// the cell lies below the tangent plane of n.
    T min_cosine(std::size_t d, const Vec3<T>& n) const { return min_cosine(bounds(d), n); }

private:
    int n_phi_, n_theta_;
    bool hemisphere_;
};

/// Which main part of section 3.3 to use.
enum class EnvironmentMainPart {
    radiance,  // eq. 3.5: g = L_env(w) a_d / |Omega_d| (diffuse or moderately specular)
    brdf       // eq. 3.6: g = L~_d fr(w) cos(theta) (smooth environment, specular BRDF)
};

/// Section 3.3's choice of main part for one cell, "selected separately for each sample": eq. 3.5
/// neglects the variation of fr cos over the cell, eq. 3.6 that of the radiance, so the main part
/// kept is the one whose neglected factor varies less there, measured by the relative variances
/// (variance / mean^2 over the cell) of the radiance and of fr cos. ("If the environment map has
/// high variation in the subdomain and the point to be rendered is diffuse or moderately
/// specular, then option one is better ... when the environment map is smooth and the BRDF is
/// strongly specular, then option two.")
template <Scalar T>
EnvironmentMainPart choose_environment_main_part(T radiance_relative_variance, T brdf_cos_relative_variance) {
    return brdf_cos_relative_variance <= radiance_relative_variance ? EnvironmentMainPart::radiance
                                                                    : EnvironmentMainPart::brdf;
}

/// Cell averages L~_d of an environment, by a q x q midpoint rule in (phi, cos theta), which is
/// exact for radiance linear in cos(theta) and constant in phi within a cell. Computed once.
template <Scalar T, std::size_t N, class Environment>
void environment_cell_averages(const SphereCells<T>& cells, Environment&& environment,
                               std::span<Spectrum<T, N>> averages, int q = 8) {
    if (averages.size() != cells.count() || q <= 0)
        throw Error("glint::environment_cell_averages: need one output per cell (" +
                    std::to_string(cells.count()) + ") and q > 0");
    for (std::size_t d = 0; d < cells.count(); ++d) {
        Spectrum<T, N> sum(T(0));
        for (int a = 0; a < q; ++a)
            for (int b = 0; b < q; ++b)
                sum += environment(cells.sample(d, Vec2<T>((T(a) + T(0.5)) / T(q), (T(b) + T(0.5)) / T(q))));
        averages[d] = sum / T(q * q);
    }
}

/// Environment lighting of a point by the combined estimator, cell by cell (section 3.3).
/// Directions are in the local frame of the cells (z = the receiver's normal for the closed-form
/// diffuse a_d). environment(w) -> Spectrum; brdf(w) -> fr; cell_albedo[d] = a_d = integral over
/// cell d of fr cos (fr * cells.cosine_integral(d) for a diffuse fr); averages[d] = L~_d;
/// visible(w) -> bool. `uniforms` holds samples_per_cell pairs for each cell in turn. Returns
/// the sums over the cells. No allocation.
template <Scalar T, std::size_t N, class Environment, class Brdf, class Visibility>
CorrelatedResult<T, N> correlated_environment(
    const SphereCells<T>& cells, std::span<const Spectrum<T, N>> averages,
    std::span<const Spectrum<T, N>> cell_albedo, Environment&& environment, Brdf&& brdf,
    Visibility&& visible, std::span<const Vec2<T>> uniforms, std::size_t samples_per_cell,
    EnvironmentMainPart part, LambdaEstimate form = LambdaEstimate::regression) {
    CorrelatedResult<T, N> out;
    const T omega = cells.solid_angle();  // 1 / p
    const std::size_t cell_count = std::min({cells.count(), averages.size(), cell_albedo.size()});
    for (std::size_t d = 0; d < cell_count && (d + 1) * samples_per_cell <= uniforms.size(); ++d) {
        std::array<CorrelatedStats<T>, N> stats{};
        for (std::size_t k = 0; k < samples_per_cell; ++k) {
            const Vec3<T> w = cells.sample(d, uniforms[d * samples_per_cell + k]);
            const T cos_theta = std::max(w.z, T(0));
            const Spectrum<T, N> L = environment(w);
            const Spectrum<T, N> fr_cos = brdf(w) * cos_theta;
            const Spectrum<T, N> f = visible(w) ? L * fr_cos * omega : Spectrum<T, N>(T(0));
            const Spectrum<T, N> g = part == EnvironmentMainPart::radiance
                                         ? L * cell_albedo[d]  // (a_d / omega) * omega
                                         : averages[d] * fr_cos * omega;
            for (std::size_t l = 0; l < N; ++l) stats[l].add(f[l], g[l]);
        }
        for (std::size_t l = 0; l < N; ++l) {
            const T J = averages[d][l] * cell_albedo[d][l];
            const T lambda = stats[l].lambda(J, form);
            out.main_part[l] += J;
            out.lambda[l] += lambda / T(cell_count);
            out.combined[l] += stats[l].estimate(J, lambda);
            out.importance[l] += stats[l].importance_estimate();
            out.correlated[l] += stats[l].correlated_estimate(J);
        }
    }
    return out;
}

}  // namespace glint
