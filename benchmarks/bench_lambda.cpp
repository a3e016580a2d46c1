// bench_lambda: bias and variance of the combined correlated estimator (Szécsi 2009, §3.1) as
// its weight lambda is pooled over pixel neighbourhoods of radius 0, 1, 2 (Szécsi 2009, §3.1.1),
// and statistical lambda (eq. 3.3) against lambda = the fractional visibility (Szécsi 2009,
// §3.2, where it sets the weight of direct lighting).
//
//   taskset -c 1 ./build/benchmarks/bench_lambda --csv docs/lambda_arealight.csv
//   taskset -c 1 ./build/benchmarks/bench_lambda --scene cornell --csv docs/lambda_cornell.csv
//
// Direct illumination only (max depth 1, as bench_convergence's arealight comparison): the
// rest of the path is noise every method shares and would hide what lambda does. Camera rays
// through pixel centres, so each pixel estimates one integral, from spp x light-samples light
// points (Szécsi 2009 compares at 10 light samples). Every method renders `renders` independent
// images (render r has the same hashed seed for every method, see series_seed: common random
// numbers).
// Per pixel p and band, with d_r = Y_r - ref (ref: the reference image):
//   variance  s_p^2 = the sample variance of Y_r over the renders (one render's variance)
//   bias^2    U_p = (sum_{r != r'} d_r d_r') / (R (R - 1)), unbiased for (E Y - ref)^2, minus
//             the reference's own variance of its mean (its variance layer);
//             U_p = (mean d)^2 - s_p^2 / R, i.e. bias^2 = MSE - variance
//   MSE       mean_r d_r^2 minus the reference's variance = variance + bias^2
//   mean bias mean d (signed; averaged over pixels, biases of opposite sign cancel)
// each averaged over the pixels and the three bands, over all pixels and over the penumbra
// (fractional visibility strictly between 0.02 and 0.98, from a render of 16 x 64 light
// samples). Standard errors: the delete-a-group jackknife (Efron and Tibshirani 1993, ch. 11)
// over the renders in 32 groups (the renders are independent, so it holds the correlation
// between pooled neighbours), with the reference's noise added in quadrature (per pixel-band
// 4 (m - ref)^2 v_ref + 2 v_ref^2 for bias^2 and MSE, v_ref for the mean bias).
// The reference is unbiased: lambda = 1 (correlated sampling, eq. 3.1 with a constant lambda;
// its variance a fiftieth of importance sampling's or less on arealight, zero where the light is fully
// visible) from --ref-renders independent renders of 64 light samples, its own seeds. Methods: importance (lambda = 0) and
// correlated (lambda = 1) are unbiased, so their bias^2 must be zero within its standard
// error -- the check that the measurement separates bias from variance; then combined with
// statistical and visibility lambda at radius 0, 1, 2.
// --seed-check (alone) prints how dependent RandomSampler's streams from related seeds are
// (see series_seed), the reason every render here has a hashed seed.
// CSV columns: scene,region,method,lambda,radius,renders,spp,light_samples,variance,
// variance_se,bias2,bias2_se,mean_bias,mean_bias_se,mse,mse_se,rmse,rmse_se,bias2_share,
// bias2_minus_correlated, bias2_minus_correlated_se (bias^2 minus that of lambda = 1, paired:
// the reference's own error cancels but for a cross term, so a bias pooling adds is resolved
// more finely than by the bias^2 column).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/tracer/correlated_direct.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

using Accel = MeshBvh<MollerTrumbore<float>, 8>;
using Tracer = PathTracer<Accel, RandomSampler<float>, CorrelatedDirect<float>>;

/// The image's and the tracer's settings.
struct Settings {
    RenderSettings image;
    PathTracerSettings<float> tracer{.roulette = Roulette<float, 3>::classic()};
};

struct Config {
    std::string scene = "arealight", csv;
    int size = 64, spp = 1, light_samples = 10, renders = 1024, ref_renders = 1024, depth = 1, groups = 32;
    std::uint64_t seed = 0;
};

struct Method {
    std::string name, lambda;  // lambda: "0", "1", "statistical" or "visibility"
    DirectEstimator estimator;
    LambdaSource source;
    int radius;
};

std::vector<Method> methods() {
    std::vector<Method> m{{"importance", "0", DirectEstimator::importance, LambdaSource::statistical, -1},
                          {"correlated", "1", DirectEstimator::correlated, LambdaSource::statistical, -1}};
    for (LambdaSource src : {LambdaSource::statistical, LambdaSource::visibility})
        for (int r = 0; r <= 2; ++r) {
            const std::string l = src == LambdaSource::statistical ? "statistical" : "visibility";
            m.push_back({"combined " + l + " r" + std::to_string(r), l, DirectEstimator::combined, src, r});
        }
    return m;
}

RenderResult render(const Scene<float>& scene, const Accel& accel, Settings s, const Method& m, std::uint64_t seed) {
    s.tracer.lambda_filter_radius = m.radius;
    const Tracer tracer(scene, accel, CorrelatedDirect<float>(scene, s.tracer, m.estimator, m.source),
                        MisEnvironment<float>(scene), s.tracer);
    return render_image(scene, s.image, tracer, RandomSampler<float>(seed));
}

/// One method's renders, as differences d = Y_r - ref to the reference, pixel-band by
/// pixel-band: sums of d and d^2 over all renders and over each jackknife group.
struct Renders {
    int n = 0;
    std::vector<double> s1, s2;
    std::vector<std::vector<double>> g1, g2;  // [group][3 p + c]
    Renders(std::size_t size, int groups)
        : s1(size, 0.0), s2(size, 0.0), g1(std::size_t(groups), s1), g2(std::size_t(groups), s1) {}
    void add(int group, std::size_t i, double d) {
        s1[i] += d, s2[i] += d * d;
        g1[std::size_t(group)][i] += d, g2[std::size_t(group)][i] += d * d;
    }
};

struct Estimate {
    double value = 0, se = 0;
};

struct Summary {
    Estimate variance, bias2, mean_bias, mse, rmse;
};

/// The four statistics from the per-pixel sums of n renders over the masked pixel-bands.
std::array<double, 4> statistics(const std::vector<double>& s1, const std::vector<double>& s2, double n,
                                 const std::vector<std::size_t>& idx, double ref_var) {
    double var = 0, u = 0, bias = 0;
    for (std::size_t i : idx) {
        var += (s2[i] - s1[i] * s1[i] / n) / (n - 1.0);
        u += (s1[i] * s1[i] - s2[i]) / (n * (n - 1.0));
        bias += s1[i] / n;
    }
    const double k = double(idx.size());
    var /= k, u /= k, bias /= k;
    return {var, u - ref_var, bias, var + u - ref_var};
}

/// Statistics over the pixel-bands `idx` with delete-a-group jackknife standard errors over
/// the renders (equal groups) and the reference's noise (ref_v: its variance layer) added in
/// quadrature.
Summary summarize(const Renders& rs, const std::vector<std::size_t>& idx, const std::vector<double>& ref_v) {
    const double n = double(rs.n), k = double(idx.size()), groups = double(rs.g1.size());
    double ref_var = 0;
    for (std::size_t i : idx) ref_var += ref_v[i] / k;
    const auto full = statistics(rs.s1, rs.s2, n, idx, ref_var);
    // Leave-one-group-out values of the four statistics and of the RMSE.
    std::vector<std::array<double, 5>> loo(rs.g1.size());
    std::vector<double> a(rs.s1.size()), b(rs.s2.size());
    for (std::size_t g = 0; g < rs.g1.size(); ++g) {
        for (std::size_t i : idx) a[i] = rs.s1[i] - rs.g1[g][i], b[i] = rs.s2[i] - rs.g2[g][i];
        const auto s = statistics(a, b, n - n / groups, idx, ref_var);
        loo[g] = {s[0], s[1], s[2], s[3], std::sqrt(std::max(s[3], 0.0))};
    }
    std::array<double, 5> se{};
    for (std::size_t j = 0; j < 5; ++j) {
        double mean = 0, ss = 0;
        for (const auto& l : loo) mean += l[j] / groups;
        for (const auto& l : loo) ss += (l[j] - mean) * (l[j] - mean);
        se[j] = std::sqrt((groups - 1.0) / groups * ss);
    }
    // The reference's noise: bias^2 and MSE hold -2 (m - I)(ref - I) + (ref - I)^2 - v_ref per
    // pixel-band, of variance about 4 (m - ref)^2 v_ref + 2 v_ref^2; the mean bias holds -(ref - I).
    double ref_sq = 0, ref_lin = 0;
    for (std::size_t i : idx) {
        const double m = rs.s1[i] / n;
        ref_sq += 4.0 * m * m * ref_v[i] + 2.0 * ref_v[i] * ref_v[i];
        ref_lin += ref_v[i];
    }
    const double se_sq = std::sqrt(ref_sq) / k, se_lin = std::sqrt(ref_lin) / k;
    const double mse = full[3], rmse = std::sqrt(std::max(mse, 0.0));
    Summary out;
    out.variance = {full[0], se[0]};
    out.bias2 = {full[1], std::hypot(se[1], se_sq)};
    out.mean_bias = {full[2], std::hypot(se[2], se_lin)};
    out.mse = {mse, std::hypot(se[3], se_sq)};
    out.rmse = {rmse, std::hypot(se[4], rmse > 0 ? se_sq / (2.0 * rmse) : 0.0)};
    return out;
}

/// bias^2 of `a` minus bias^2 of `b` (an unbiased method), paired: the reference's own error,
/// common to both, cancels but for the cross term -2 (m_a - m_b)(ref - I), whose variance
/// 4 (m_a - m_b)^2 v_ref per pixel-band is added in quadrature to the jackknife's.
Estimate paired_bias2(const Renders& a, const Renders& b, const std::vector<std::size_t>& idx,
                      const std::vector<double>& ref_v) {
    const double n = double(a.n), groups = double(a.g1.size()), k = double(idx.size());
    auto u = [&](auto&& sum1a, auto&& sum2a, auto&& sum1b, auto&& sum2b, double m) {
        double d = 0;
        for (std::size_t i : idx)
            d += (sum1a(i) * sum1a(i) - sum2a(i) - sum1b(i) * sum1b(i) + sum2b(i)) / (m * (m - 1.0));
        return d / k;
    };
    const double full = u([&](std::size_t i) { return a.s1[i]; }, [&](std::size_t i) { return a.s2[i]; },
                          [&](std::size_t i) { return b.s1[i]; }, [&](std::size_t i) { return b.s2[i]; }, n);
    std::vector<double> loo;
    for (std::size_t g = 0; g < a.g1.size(); ++g)
        loo.push_back(u([&](std::size_t i) { return a.s1[i] - a.g1[g][i]; }, [&](std::size_t i) { return a.s2[i] - a.g2[g][i]; },
                        [&](std::size_t i) { return b.s1[i] - b.g1[g][i]; }, [&](std::size_t i) { return b.s2[i] - b.g2[g][i]; },
                        n - n / groups));
    double mean = 0, ss = 0, ref = 0;
    for (double l : loo) mean += l / groups;
    for (double l : loo) ss += (l - mean) * (l - mean);
    for (std::size_t i : idx) ref += 4.0 * std::pow((a.s1[i] - b.s1[i]) / n, 2) * ref_v[i];
    return {full, std::hypot(std::sqrt((groups - 1.0) / groups * ss), std::sqrt(ref) / k)};
}

Config parse(int argc, char** argv) {
    Config cfg;
    cli::App app("bench_lambda: correlated sampling's lambda pooled over pixels (Szecsi 2009, 3.1.1) and statistical "
                 "lambda, bias and variance over many renders (--seed-check alone: the seeds' stream dependence)");
    // --quick first: the flags after it in this list (any given with it) override its sizes.
    app.flag("--quick", [&cfg] { cfg.size = 16, cfg.renders = 8, cfg.ref_renders = 16; },
             "a smoke run: 16 x 16, 8 renders, 16 reference renders");
    cli::text(app, "--scene", cfg.scene, "a built-in scene", "NAME");
    cli::output(app, "--csv", cfg.csv, "write the rows as CSV");
    cli::number(app, "--size", cfg.size, 4, 1 << 20, "image width and height");
    cli::number(app, "--spp", cfg.spp, 1, 1 << 20, "samples per pixel of a render");
    cli::number(app, "--light-samples", cfg.light_samples, 2, 1 << 20, "light samples per vertex");
    cli::number(app, "--renders", cfg.renders, 3, 1 << 20, "renders per method");
    cli::number(app, "--ref-renders", cfg.ref_renders, 1, 1 << 20, "reference renders");
    cli::number(app, "--depth", cfg.depth, 1, 1 << 20, "path length");
    cli::number(app, "--seed", cfg.seed, std::uint64_t(0), ~std::uint64_t(0), "random seed");
    if (!cli::parse(app, argc, argv)) std::exit(0);
    // Jackknife groups of equal size: at most 32, renders rounded up to a multiple.
    cfg.groups = std::min(32, cfg.renders);
    cfg.renders = (cfg.renders + cfg.groups - 1) / cfg.groups * cfg.groups;
    return cfg;
}

/// The seed of render r of a series (splitmix64, Steele, Lea, Flood 2014, applied twice).
/// RandomSampler seeds that are related (consecutive integers, or the pixel-sample indices it
/// XORs into one seed) start PCG32 states that differ by a fixed amount and give dependent
/// streams: measured here, the mean of a dimension's first uniform over 1024 consecutive seeds
/// varies only 0.34-0.76 times as much as for independent draws (hashed seeds: 0.97-1.02), which
/// made bias^2 of unbiased methods come out several standard errors below 0.
std::uint64_t series_seed(std::uint64_t series, std::uint64_t r) {
    return detail::mix_bits(detail::mix_bits(series + 0x9e3779b97f4a7c15ULL) ^ r);
}

/// --seed-check: how dependent RandomSampler's streams are. For 4096 pixels and the first four
/// dimensions, the variance of the mean of u - 1/2 over 1024 streams, relative to independent
/// draws' 1/(12 * 1024): streams from consecutive seeds (index 0), from consecutive
/// pixel-sample indices of one seed, and from series_seed's hashed seeds.
void seed_check() {
    const int R = 1024, P = 4096;
    const char* names[3] = {"consecutive seeds", "consecutive pixel-sample indices", "hashed seeds"};
    for (int mode = 0; mode < 3; ++mode) {
        std::array<double, 4> v{};
        for (int p = 0; p < P; ++p) {
            std::array<double, 4> sum{};
            for (int r = 0; r < R; ++r) {
                RandomSampler<float> sampler(mode == 0 ? std::uint64_t(r) : mode == 1 ? 1 : series_seed(7, std::uint64_t(r)));
                sampler.start_pixel_sample(p % 64, p / 64, mode == 1 ? std::uint64_t(r) : 0);
                for (double& x : sum) x += double(sampler.get_1d()) - 0.5;
            }
            for (std::size_t k = 0; k < 4; ++k) v[k] += (sum[k] / R) * (sum[k] / R) / P;
        }
        std::printf("%-34s variance of the mean / independent, dimensions 0-3: %.3f %.3f %.3f %.3f (SE about 0.02)\n",
                    names[mode], v[0] * 12 * R, v[1] * 12 * R, v[2] * 12 * R, v[3] * 12 * R);
    }
}

/// Pixel-band indices of the whole image and of the penumbra (fractional visibility in
/// (0.02, 0.98), from the lambda layer of a visibility-lambda render at 64 light samples).
std::array<std::vector<std::size_t>, 2> regions(const Scene<float>& scene, const Accel& accel, Settings s) {
    s.tracer.light_samples = 64;
    s.image.spp = 16;
    const RenderResult v = render(scene, accel, s, {"visibility", "visibility", DirectEstimator::combined,
                                                    LambdaSource::visibility, 0}, series_seed(0x5e6104, 0));
    std::array<std::vector<std::size_t>, 2> out;
    const FilmLayer* lambda = v.layer("lambda");
    if (!lambda) throw Error("bench_lambda: correlated sampling wrote no lambda layer");
    for (std::size_t p = 0; p < lambda->pixels.size(); ++p)
        for (std::size_t c = 0; c < 3; ++c) {
            out[0].push_back(3 * p + c);
            const float f = lambda->pixels.pixels[p][0];
            if (f > 0.02f && f < 0.98f) out[1].push_back(3 * p + c);
        }
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc == 2 && std::string(argv[1]) == "--seed-check") {
            seed_check();
            return 0;
        }
        const Config cfg = parse(argc, argv);
        const Scene<float> scene = builtin_scene<float>(cfg.scene);
        if (scene.features().environment || scene.features().point_lights || !scene.features().area_lights)
            throw Error("bench_lambda: the scene '" + cfg.scene + "' must have area lights and no environment or point lights");
        const Accel accel(scene.triangles);
        Settings s;
        s.image.width = s.image.height = cfg.size;
        s.image.spp = cfg.spp;
        s.image.threads = 1;
        s.image.pixel_jitter = false;
        s.tracer.max_depth = cfg.depth;
        s.tracer.light_samples = cfg.light_samples;

        // The reference: the mean of --ref-renders independent renders of 1 spp (each its own hashed
        // seed, see series_seed), and the variance of that mean.
        Settings rs = s;
        rs.image.spp = 1;
        rs.tracer.light_samples = 64;
        const std::size_t size = 3 * std::size_t(cfg.size) * std::size_t(cfg.size);
        std::vector<double> ref(size, 0.0), ref_v(size, 0.0);
        double ref_seconds = 0;
        for (int r = 0; r < cfg.ref_renders; ++r) {
            const RenderResult img = render(scene, accel, rs, methods()[1], series_seed(2 * cfg.seed + 1, std::uint64_t(r)));
            ref_seconds += img.seconds;
            for (std::size_t i = 0; i < size; ++i) {
                const double y = img.image.pixels[i / 3][i % 3];
                ref[i] += y, ref_v[i] += y * y;
            }
        }
        const double nr = double(cfg.ref_renders);
        for (std::size_t i = 0; i < size; ++i) {
            ref[i] /= nr;
            ref_v[i] = nr > 1 ? std::max(0.0, ref_v[i] / nr - ref[i] * ref[i]) / (nr - 1.0) : 0.0;
        }
        const auto region = regions(scene, accel, s);
        std::printf("%s: %dx%d, spp %d x %d light samples, %d renders, depth %d; reference %d x 64 light samples "
                    "(%.1f s); penumbra %zu of %zu pixels\n",
                    cfg.scene.c_str(), cfg.size, cfg.size, cfg.spp, cfg.light_samples, cfg.renders, cfg.depth,
                    cfg.ref_renders, ref_seconds, region[1].size() / 3, region[0].size() / 3);

        const std::vector<Method> ms = methods();
        std::vector<Renders> all(ms.size(), Renders(ref_v.size(), cfg.groups));
        for (int r = 0; r < cfg.renders; ++r)  // renders outer, methods inner: load drifts hit all alike
            for (std::size_t j = 0; j < ms.size(); ++j) {
                const RenderResult img = render(scene, accel, s, ms[j], series_seed(2 * cfg.seed, std::uint64_t(r)));
                for (std::size_t i = 0; i < size; ++i)
                    all[j].add(r % cfg.groups, i, double(img.image.pixels[i / 3][i % 3]) - ref[i]);
                ++all[j].n;
            }

        std::ofstream csv;
        if (!cfg.csv.empty()) {
            csv.open(cfg.csv);
            if (!csv) throw Error("bench_lambda: cannot write " + cfg.csv);
            csv << "scene,region,method,lambda,radius,renders,spp,light_samples,variance,variance_se,bias2,bias2_se,"
                   "mean_bias,mean_bias_se,mse,mse_se,rmse,rmse_se,bias2_share,bias2_minus_correlated,"
                   "bias2_minus_correlated_se\n";
        }
        const char* names[2] = {"all", "penumbra"};
        for (int g = 0; g < 2; ++g) {
            std::printf("\n%s pixels\n| method | variance | bias^2 | bias^2 - lambda=1's | mean bias | MSE | RMSE | "
                        "bias^2/MSE |\n|---|---|---|---|---|---|---|---|\n", names[g]);
            for (std::size_t j = 0; j < ms.size(); ++j) {
                const Summary x = summarize(all[j], region[std::size_t(g)], ref_v);
                const Estimate paired = paired_bias2(all[j], all[1], region[std::size_t(g)], ref_v);
                std::printf("| %s | %.4g ± %.2g | %.3g ± %.2g | %.3g ± %.2g | %.3g ± %.2g | %.4g ± %.2g | %.4g ± %.2g | %.2f%% |\n",
                            ms[j].name.c_str(), x.variance.value, x.variance.se, x.bias2.value, x.bias2.se, paired.value,
                            paired.se, x.mean_bias.value, x.mean_bias.se, x.mse.value, x.mse.se, x.rmse.value, x.rmse.se,
                            100.0 * x.bias2.value / x.mse.value);
                if (csv)
                    csv << cfg.scene << ',' << names[g] << ',' << ms[j].name << ',' << ms[j].lambda << ',' << ms[j].radius
                        << ',' << cfg.renders << ',' << cfg.spp << ',' << cfg.light_samples << ',' << x.variance.value
                        << ',' << x.variance.se << ',' << x.bias2.value << ',' << x.bias2.se << ',' << x.mean_bias.value
                        << ',' << x.mean_bias.se << ',' << x.mse.value << ',' << x.mse.se << ',' << x.rmse.value << ','
                        << x.rmse.se << ',' << x.bias2.value / x.mse.value << ',' << paired.value << ',' << paired.se
                        << '\n';
            }
        }
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_lambda: %s\n", e.what());
        return 1;
    }
}
