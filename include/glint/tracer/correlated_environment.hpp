// glint/tracer/correlated_environment.hpp: CorrelatedEnvironment, Szécsi 2009, §3.3's environment
// lighting by multiple correlated sampling as an environment-lighting policy
// (tracer/lighting.hpp's EnvironmentLighting, in place of MisEnvironment).
//
// At each vertex, K directions w_k are drawn from the map's importance density p (the samples
// MisEnvironment draws one of); f = L(w) fr(w) cos V(w) is the integrand over the whole sphere
// and g the main part, which neglects the visibility V (§3.3). The sphere is split
// into world-fixed cells Omega_d of equal solid angle (SphereCells, §3.3.1, with its pole
// on the map's up axis), and in each cell g is one of §3.3's two main parts:
//   eq. 3.5  g = L(w) c_d,  c_d a constant per cell: the mean of fr cos over a 2x2 stencil of
//            the cell (§3.3's a_d / |Omega_d|). J_d = L~_d c_d |Omega_d| is the exact integral of
//            g for any constant c_d, so only the cell average L~_d must be exact: it is computed
//            once from the map's pixels (EnvironmentMap::integrate), as §3.3 says ("computed once
//            when the environment map is loaded").
//   eq. 3.6  g = L~_d fr~ (n . w), fr~ = kd / pi (the diffuse part, as §3.2's fr~;
//            the whole BRDF of a Lambertian surface). J_d = L~_d fr~ n . V_d with V_d the cell's
//            closed-form direction integral (SphereCells::direction_integral): the exact integral
//            of g, whose cosine is signed. Only where the whole cell lies above the tangent plane
//            is that cosine fr cos's (below it f = 0), so cells the plane cuts use eq. 3.5.
// The main part is chosen per cell and vertex by choose_environment_main_part (§3.3: "the optimal
// alternative can be selected separately for each sample"), from the radiance's relative variance
// over the cell (once per map) and fr cos's over the stencil (per vertex). Neither depends on the
// random samples, so the choice adds no bias. Then (§3.1, CorrelatedStats)
//   importance  mean f/p                        (lambda = 0)
//   correlated  mean f/p + J - mean g/p         (lambda = 1, unbiased)
//   combined    1/K sum_k [f_k/p_k + lambda_-k (J - g_k/p_k)], lambda_-k estimated from the other
//               K - 1 samples (eq. 3.3's regression form) and clamped to [0, 1]
//               (leave_one_out_estimate): unbiased, where lambda from all K samples, as
//               eq. 3.3 writes it, is not, and unclamped it multiplies J - mean g/p without
//               bound where most samples fall in the sun's pixels and the g/p are nearly equal.
// The estimate covers the whole sphere, so a BRDF-sampled ray that escapes from a vertex whose
// lights were sampled adds nothing (escaped() returns 0 there).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/sampling/correlated.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/correlated_direct.hpp>
#include <glint/tracer/environment.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>

namespace glint {

/// How CorrelatedEnvironment samples: its cells, samples per vertex and estimator. The
/// constructor checks the ranges below and throws glint::Error outside them.
struct CorrelatedEnvironmentSettings {
    /// Cells in azimuth of the world-fixed SphereCells grid; n_phi * n_theta <= 128.
    int n_phi = 8, n_theta = 4;
    /// \var n_theta
    /// Cells in polar angle (equal solid angle per cell); n_phi * n_theta <= 128.

    /// K directions per vertex from the map's importance (1 .. 64); lambda_-k is estimated
    /// from K - 1 of them (Szécsi 2009's figures take 10-20 samples per cell).
    int samples = 16;
    /// importance, correlated or combined, as in the header comment (default: combined).
    DirectEstimator estimator = DirectEstimator::combined;
    /// One main part in every cell (eq. 3.6 falls back to eq. 3.5 where the tangent plane cuts
    /// the cell), or none: the choice per cell and vertex.
    std::optional<EnvironmentMainPart> main_part;
};

/// The environment-lighting policy of Szécsi 2009, §3.3 (see the header comment): an
/// EnvironmentLighting that estimates the map's reflected radiance at each vertex with K
/// correlated samples. Needs a scene with an environment map; read-only after construction.
template <Scalar T = float>
class CorrelatedEnvironment {
public:
    /// Most cells, n_phi * n_theta (per-vertex state lives in stack arrays of this size).
    static constexpr std::size_t max_cells = 128, max_samples = 64;
    /// \var max_samples
    /// Most directions per vertex (CorrelatedEnvironmentSettings::samples).


    /// A cell's main part at one vertex: g(w) = L(w) weight (eq. 3.5) or weight (n . w) (eq. 3.6).
    struct CellPart {
        EnvironmentMainPart part = EnvironmentMainPart::radiance;  ///< Which of eqs. 3.5 and 3.6.
        Rgb<T> weight{T(0)};  ///< c_d for eq. 3.5, L~_d fr~ for eq. 3.6.
    };

    /// The policy for `scene`'s environment map; precomputes each cell's average radiance
    /// and its variance from the map's pixels. Throws glint::Error when the scene has no map
    /// or `s` is out of range.
    CorrelatedEnvironment(const Scene<T>& scene, const CorrelatedEnvironmentSettings& s = {})
        : env_(scene.environment ? &*scene.environment : nullptr), cells_(s.n_phi, s.n_theta, false), settings_(s) {
        if (!env_) throw Error("glint::CorrelatedEnvironment: the scene '" + scene.name + "' has no environment map");
        if (cells_.count() > max_cells || s.samples < 1 || std::size_t(s.samples) > max_samples)
            throw Error("glint::CorrelatedEnvironment: at most " + std::to_string(max_cells) + " cells and 1.." +
                        std::to_string(max_samples) + " samples, got " + std::to_string(cells_.count()) + " cells and " +
                        std::to_string(s.samples) + " samples");
        precompute_cells();
    }

    /// The settings it was built with.
    const CorrelatedEnvironmentSettings& settings() const { return settings_; }
    /// The world-fixed cells Omega_d (pole on the map's up axis).
    const SphereCells<T>& cells() const { return cells_; }

    /// Radiance the environment reflects at `sp` towards its viewer, by the configured
    /// estimator over K map samples (K 2D numbers from `sampler`, K shadow rays through
    /// `queries`).
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S& sampler, Q& queries) const {
        std::array<Vec2<T>, max_samples> u;
        const std::size_t k = std::size_t(settings_.samples);
        for (std::size_t i = 0; i < k; ++i) u[i] = sampler.get_2d();
        std::array<CellPart, max_cells> parts;
        Rgb<T> J(T(0));
        const bool main = settings_.estimator != DirectEstimator::importance;
        if (main) J = main_parts(sp, std::span<CellPart>(parts.data(), cells_.count()));
        std::array<std::array<T, max_samples>, 3> fs{}, gs{};
        for (std::size_t i = 0; i < k; ++i) {
            T pdf;
            const Vec3<T> w = env_->sample(u[i], pdf);
            if (!(pdf > T(0))) continue;
            const Rgb<T> L = env_->eval(w) / pdf;
            const Vec3<T> wl = sp.frame.to_local(w);
            Rgb<T> f(T(0)), g(T(0));
            if (wl.z > T(0)) f = sp.brdf->f(wl) * (wl.z);
            if (f.max() > T(0) && queries.unoccluded(spawn(sp, w))) f *= L;
            else f = Rgb<T>(T(0));
            if (main) g = main_part_value(parts[cells_.cell_of(to_cells(w))], L, glm::dot(sp.n, w) / pdf);
            for (std::size_t c = 0; c < 3; ++c) fs[c][i] = f[c], gs[c][i] = g[c];
        }
        Rgb<T> out;
        for (std::size_t c = 0; c < 3; ++c) {
            const std::span<const T> fc(fs[c].data(), k), gc(gs[c].data(), k);
            T mean_f = 0, mean_g = 0;
            for (std::size_t i = 0; i < k; ++i) mean_f += fc[i] / T(k), mean_g += gc[i] / T(k);
            if (settings_.estimator == DirectEstimator::importance) out[c] = mean_f;
            else if (settings_.estimator == DirectEstimator::correlated) out[c] = mean_f + J[c] - mean_g;
            else out[c] = leave_one_out_estimate(fc, gc, J[c]);
        }
        return out;
    }

    /// The light-sampled estimate covers the whole sphere: an escaping BRDF sample adds nothing.
    Rgb<T> escaped(const Vec3<T>& dir, const Arrival<T>& from) const {
        return from.lights_sampled ? Rgb<T>(T(0)) : env_->eval(dir);
    }

    /// Every cell's main part at sp (written to `parts`, one per cell) and J, the integral of g
    /// over the sphere.
    Rgb<T> main_parts(const ShadingPoint<T>& sp, std::span<CellPart> parts) const {
        if (parts.size() != cells_.count())
            throw Error("glint::CorrelatedEnvironment::main_parts: need " + std::to_string(cells_.count()) +
                        " cells, got " + std::to_string(parts.size()));
        const Vec3<T> n_cells = to_cells(sp.n);
        const Rgb<T> diffuse = sp.brdf->kd() / pi<T>;
        Rgb<T> J(T(0));
        for (std::size_t d = 0; d < parts.size(); ++d) {
            const Cell& cell = cell_data_[d];
            parts[d] = CellPart{};
            const T centre = glm::dot(sp.n, cell.centre);  // cheap test first, exact one where it cannot tell
            if (centre <= -cell.sin_radius || (centre < cell.sin_radius && SphereCells<T>::min_cosine(cell.bounds, -n_cells) >= T(0)))
                continue;  // below the tangent plane: g = 0
            std::array<Rgb<T>, 4> fr_cos;
            Rgb<T> c(T(0));
            for (std::size_t s = 0; s < 4; ++s) {
                const Vec3<T> wl = sp.frame.to_local(cell.stencil[s]);
                fr_cos[s] = wl.z > T(0) ? sp.brdf->f(wl) * wl.z : Rgb<T>(T(0));
                c += fr_cos[s] / T(4);
            }
            EnvironmentMainPart part = EnvironmentMainPart::radiance;
            if (centre >= cell.sin_radius || SphereCells<T>::min_cosine(cell.bounds, n_cells) >= T(0))  // eq. 3.6's J is exact
                part = settings_.main_part ? *settings_.main_part
                                           : choose_environment_main_part(cell.radiance_variation, relative_variance(fr_cos));
            if (part == EnvironmentMainPart::radiance) {
                parts[d] = {part, c};
                J += cell.average * c * cells_.solid_angle();
            } else {
                parts[d] = {part, cell.average * diffuse};
                J += cell.average * diffuse * glm::dot(sp.n, cell.direction_integral);
            }
        }
        return J;
    }

private:
    /// What is known of a cell once the map is loaded (world coordinates).
    struct Cell {
        Rgb<T> average{T(0)};             // L~_d, exact
        T radiance_variation = 0;         // relative variance of the luminance over the cell
        Vec3<T> direction_integral{T(0)};  // V_d
        std::array<Vec3<T>, 4> stencil;   // midpoints of the cell's 2x2 split in (phi, cos theta)
        typename SphereCells<T>::Bounds bounds;  // in the cells' frame
        Vec3<T> centre{T(0)};  // the cell's centre direction and sin of an angular radius about it
        T sin_radius = 1;      // that holds the whole cell: n . centre >= sin_radius: above n's plane
    };

    /// The cells' frame has its pole (z) on the map's up axis (y) and the map's azimuth: a swap
    /// of y and z, its own inverse.
    static Vec3<T> to_cells(const Vec3<T>& w) { return Vec3<T>(w.x, w.z, w.y); }

    static Rgb<T> main_part_value(const CellPart& p, const Rgb<T>& L_over_p, T cos_over_p) {
        return p.part == EnvironmentMainPart::radiance ? L_over_p * p.weight : p.weight * cos_over_p;
    }

    static T relative_variance(const std::array<Rgb<T>, 4>& v) {
        T mean = 0, square = 0;
        for (const Rgb<T>& x : v) {
            const T l = x.luminance();
            mean += l / T(4);
            square += l * l / T(4);
        }
        return mean > T(0) ? std::max(T(0), square / (mean * mean) - T(1)) : T(0);
    }

    /// sin of the largest angle between `centre` and cell d's boundary, sampled at 65 points per
    /// edge (the farthest point of a cell from its centre lies on its boundary), widened by 5%
    /// and 0.01 rad, far more than the sampling can miss; 1 for cells wider than a hemisphere.
    T sin_radius(std::size_t d, const Vec3<T>& centre) const {
        double widest = 0;
        for (int e = 0; e < 4; ++e)
            for (int k = 0; k <= 64; ++k) {
                const T t = T(k) / T(64);
                const Vec2<T> u = e == 0 ? Vec2<T>(t, T(0)) : e == 1 ? Vec2<T>(t, T(1)) : Vec2<T>(T(e - 2), t);
                const double c = std::clamp(double(glm::dot(to_cells(cells_.sample(d, u)), centre)), -1.0, 1.0);
                widest = std::max(widest, std::acos(c));
            }
        const double r = widest * 1.05 + 0.01;
        return r < pi<double> / 2 ? T(std::sin(r)) : T(1);
    }

    void precompute_cells() {
        cell_data_.resize(cells_.count());
        const int n_phi = settings_.n_phi;
        for (std::size_t d = 0; d < cells_.count(); ++d) {
            const int i = int(d % std::size_t(n_phi)), j = int(d / std::size_t(n_phi));
            const auto r = env_->integrate(double(cells_.phi_boundary(i)), double(cells_.phi_boundary(i + 1)),
                                           double(cells_.cos_boundary(j + 1)), double(cells_.cos_boundary(j)));
            Cell& c = cell_data_[d];
            const double omega = std::max(r.solid_angle, 1e-300);
            const Rgb<double> mean = r.radiance / omega;
            c.average = Rgb<T>(T(mean[0]), T(mean[1]), T(mean[2]));
            const double lum = mean.luminance();
            c.radiance_variation = lum > 0 ? T(std::max(0.0, r.luminance_squared / omega / (lum * lum) - 1.0)) : T(0);
            c.direction_integral = to_cells(cells_.direction_integral(d));
            c.bounds = cells_.bounds(d);
            c.centre = to_cells(cells_.sample(d, Vec2<T>(T(0.5))));
            c.sin_radius = sin_radius(d, c.centre);
            for (int s = 0; s < 4; ++s)
                c.stencil[std::size_t(s)] =
                    to_cells(cells_.sample(d, Vec2<T>(T(0.25) + T(0.5) * T(s & 1), T(0.25) + T(0.5) * T(s >> 1))));
        }
    }

    const EnvironmentMap<T>* env_;
    SphereCells<T> cells_;
    CorrelatedEnvironmentSettings settings_;
    std::vector<Cell> cell_data_;
};

}  // namespace glint
