// bench_occluders: occluder spheres (000 chapter 5) measured against shadow rays.
//
//   bench_occluders --fit-gssa            re-measure A(1, r/R, d/R) by Monte Carlo and fit it
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <glint/core/random.hpp>
#include <glint/occluders/gssa.hpp>

using namespace glint;

namespace {

double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Nelder-Mead minimisation of f over R^n from x0 (small, derivative-free, enough for 3-4
/// fit parameters).
std::vector<double> nelder_mead(const std::function<double(const std::vector<double>&)>& f, std::vector<double> x0,
                                int iterations = 4000) {
    const std::size_t n = x0.size();
    std::vector<std::vector<double>> s(n + 1, x0);
    for (std::size_t i = 0; i < n; ++i) s[i + 1][i] = x0[i] != 0 ? 1.2 * x0[i] : 0.1;
    std::vector<double> fs(n + 1);
    for (std::size_t i = 0; i <= n; ++i) fs[i] = f(s[i]);
    for (int it = 0; it < iterations; ++it) {
        std::vector<std::size_t> idx(n + 1);
        for (std::size_t i = 0; i <= n; ++i) idx[i] = i;
        std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return fs[a] < fs[b]; });
        const std::size_t best = idx[0], worst = idx[n], second = idx[n - 1];
        std::vector<double> c(n, 0.0);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t k = 0; k <= n; ++k)
                if (k != worst) c[i] += s[k][i] / double(n);
        auto along = [&](double t) {
            std::vector<double> p(n);
            for (std::size_t i = 0; i < n; ++i) p[i] = c[i] + t * (s[worst][i] - c[i]);
            return p;
        };
        const auto xr = along(-1.0);
        const double fr = f(xr);
        if (fr < fs[best]) {
            const auto xe = along(-2.0);
            const double fe = f(xe);
            if (fe < fr) s[worst] = xe, fs[worst] = fe;
            else s[worst] = xr, fs[worst] = fr;
        } else if (fr < fs[second]) {
            s[worst] = xr, fs[worst] = fr;
        } else {
            const auto xc = along(0.5);
            const double fc = f(xc);
            if (fc < fs[worst]) {
                s[worst] = xc, fs[worst] = fc;
            } else {
                for (std::size_t k = 0; k <= n; ++k) {
                    if (k == best) continue;
                    for (std::size_t i = 0; i < n; ++i) s[k][i] = s[best][i] + 0.5 * (s[k][i] - s[best][i]);
                    fs[k] = f(s[k]);
                }
            }
        }
    }
    std::size_t b = 0;
    for (std::size_t i = 1; i <= n; ++i)
        if (fs[i] < fs[b]) b = i;
    return s[b];
}

struct GssaSample {
    double rho, delta, a, se;  // a = A / (4 pi R^2), se its standard error
};

int fit_gssa(std::uint64_t lines) {
    std::vector<GssaSample> data;
    Pcg32 rng(2024);
    const double t0 = now();
    for (int i = 0; i < 24; ++i) {
        const double rho = (i + 1) / 24.0;
        for (int j = 0; j < 40; ++j) {
            const double x = 0.05 * std::pow(400.0, j / 39.0);  // 0.05 .. 20 (x = 2: contact)
            const double delta = (1 - rho) + x * rho;
            double se = 0;
            const double A = gssa_monte_carlo<double>(1.0, rho, delta, lines, rng, &se);
            data.push_back({rho, delta, A / (4 * pi<double>), se / (4 * pi<double>)});
        }
    }
    std::printf("measured %zu points x %llu lines in %.1f s\n", data.size(), (unsigned long long)lines, now() - t0);
    auto report = [&](const char* name, const std::function<double(double, double)>& model) {
        double sq = 0, mx = 0, sq_se = 0;
        for (const auto& s : data) {
            const double e = (model(s.rho, s.delta) - s.a) / s.a;
            sq += e * e;
            mx = std::max(mx, std::abs(e));
            sq_se += (s.se / s.a) * (s.se / s.a);
        }
        std::printf("%-44s rel. RMS error %.4f  max %.4f  (MC noise %.4f)\n", name, std::sqrt(sq / double(data.size())),
                    mx, std::sqrt(sq_se / double(data.size())));
    };
    auto rel_sq = [&](const std::function<double(double, double)>& model) {
        double sq = 0;
        for (const auto& s : data) {
            const double e = (model(s.rho, s.delta) - s.a) / s.a;
            sq += e * e;
        }
        return sq;
    };
    // 000's form: a * b^(1/delta) * rho^c + e.
    auto m000 = [](const std::vector<double>& p) {
        return [p](double rho, double delta) { return p[0] * std::pow(p[1], 1.0 / delta) * std::pow(rho, p[2]) + p[3]; };
    };
    report("000 as printed (1.1824, 0.42615, 1.972, 0.991)", m000({1.1824, 0.42615, 1.972, 0.991}));
    const auto p000 = nelder_mead([&](const std::vector<double>& p) { return rel_sq(m000(p)); }, {1.1824, 0.42615, 1.972, 0.991});
    std::printf("000's form refitted: %.5f * %.5f^(R/d) * (r/R)^%.4f + %.5f\n", p000[0], p000[1], p000[2], p000[3]);
    report("000's form refitted", m000(p000));
    auto mglint = [](const std::vector<double>& p) {
        return [p](double rho, double delta) {
            return double(gssa_fitted_unit<double>(rho, delta, GssaFit{p[0], p[1], p[2]}));
        };
    };
    const auto pg = nelder_mead([&](const std::vector<double>& p) { return rel_sq(mglint(p)); }, {0.4, 1.3, 0.0});
    std::printf("glint form: x = (d/R - 1 + r/R) / (r/R), A/4piR^2 = 1 + rho^2 (1 - exp(-%.5f x^%.5f (1 + %.5f rho)))\n",
                pg[0], pg[1], pg[2]);
    report("glint form fitted", mglint(pg));
    report("glint default fit (gssa.hpp)", [](double rho, double delta) { return double(gssa_fitted_unit<double>(rho, delta)); });
    report("minimum of sum/union/hull", [](double rho, double delta) {
        return double(gssa<double>(GssaModel::minimum, 1.0, rho, delta)) / (4 * pi<double>);
    });
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--fit-gssa")) return fit_gssa(400000);
    }
    return 0;
}
