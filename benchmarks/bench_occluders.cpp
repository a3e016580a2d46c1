// bench_occluders: occluder spheres (Szécsi 2009, ch. 5) measured against shadow rays.
//
//   bench_occluders [--quick] [--csv FILE] [--mesh FILE.obj] [--images DIR]   (images only with --images)
//       1. Delaunay build time scaling (random points and torus-knot surface samples);
//       2. sphere generation: time, and the sphere sets' hit probability for isotropic random
//          lines against the mesh's at 1000/250/100/25/10 spheres, without (Szécsi 2009's method) and
//          with radius calibration; generation time for a 100k-triangle mesh;
//       3. VPL renders (glint/vpl/integrator.hpp, the indirect part) of the torus knot (and
//          --mesh) in a box (tests/support/occluder_box.hpp): shadow rays
//          through the 8-wide BVH against occluder spheres (linear scan and kd-tree search),
//          time, speedup and relative RMSE of the VPL (indirect) illumination; the kd-tree /
//          linear crossover; side-by-side PNG images (rays | spheres | 4x difference).
//       CSV columns: scene,visibility,spheres,seconds,rel_rmse (visibility: rays,
//       spheres-linear, spheres-kdtree).
//   bench_occluders --fit-gssa    re-measure A(1, r/R, d/R) by Monte Carlo and fit it (gssa.hpp)
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/random.hpp>
#include <glint/core/image.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/io/obj.hpp>
#define GLINT_STB_IMPLEMENTATION  // stb_image_write's functions, compiled in this file
#include <glint/io/png.hpp>
#include <glint/occluders/delaunay.hpp>
#include <glint/occluders/gssa.hpp>
#include <glint/occluders/spheres.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/vpl/integrator.hpp>
#include "image_error.hpp"
#include "occluder_box.hpp"
#include "tree_scenes.hpp"

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

/// CPU seconds of this process: the renders are single-threaded, and on a shared machine CPU
/// time is far less disturbed by other jobs than wall time (the speedups are ratios of it).
double now() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
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
    // The dissertation's form (Szécsi 2009, §5.2.3): a * b^(1/delta) * rho^c + e.
    auto m_printed = [](const std::vector<double>& p) {
        return [p](double rho, double delta) { return p[0] * std::pow(p[1], 1.0 / delta) * std::pow(rho, p[2]) + p[3]; };
    };
    report("Szecsi 2009 as printed (1.1824, 0.42615, 1.972, 0.991)", m_printed({1.1824, 0.42615, 1.972, 0.991}));
    const auto refit =
        nelder_mead([&](const std::vector<double>& p) { return rel_sq(m_printed(p)); }, {1.1824, 0.42615, 1.972, 0.991});
    std::printf("Szecsi 2009's form refitted: %.5f * %.5f^(R/d) * (r/R)^%.4f + %.5f\n", refit[0], refit[1], refit[2], refit[3]);
    report("Szecsi 2009's form refitted", m_printed(refit));
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


/// --mesh: io/obj.hpp's loader, in double.
Mesh<double> read_obj(const std::string& path) {
    const ObjMesh obj = load_obj(path);
    Mesh<double> m(obj.triangles.size());
    for (std::size_t i = 0; i < m.size(); ++i)
        for (std::size_t k = 0; k < 3; ++k) m[i][k] = Vec3d(obj.triangles[i][k]);
    if (m.empty()) throw Error(path + " has no faces");
    return m;
}

// ---------------------------------------------------------------------------------------

struct Options {
    bool quick = false;
    std::string csv, mesh, images;  // images: written only when --images DIR is given
};

struct CsvRow {
    std::string scene, visibility;
    std::size_t spheres;
    double seconds, rel_rmse;
};

void delaunay_scaling(const Options& o) {
    std::printf("\n== Delaunay build time (Bowyer-Watson, exact predicates; CPU time) ==\n%10s %12s %12s %14s\n",
                "points", "set", "seconds", "us/point");
    std::vector<std::size_t> sizes = {1000, 10000, 100000};
    if (o.quick) sizes = {1000, 10000};
    const auto knot = make_torus_knot<double>();
    for (std::size_t n : sizes) {
        Pcg32 rng(7);
        std::vector<Vec3d> pts(n);
        for (auto& p : pts) p = Vec3d(rng.uniform<double>(), rng.uniform<double>(), rng.uniform<double>());
        double t0 = now();
        const Delaunay<double> d{std::span<const Vec3d>(pts)};
        const double random_s = now() - t0;
        std::printf("%10zu %12s %12.3f %14.2f\n", n, "random", random_s, 1e6 * random_s / double(n));
        std::vector<Vec3d> nrm;
        sample_surface<double>(knot, n, 3, pts, nrm);
        t0 = now();
        const Delaunay<double> s{std::span<const Vec3d>(pts)};
        const double knot_s = now() - t0;
        std::printf("%10zu %12s %12.3f %14.2f\n", n, "knot-surface", knot_s, 1e6 * knot_s / double(n));
    }
}

/// Hit-probability check: relative error of the sphere sets against the mesh.
void hit_probability(const std::string& name, const Mesh<double>& mesh, const Options& o) {
    const std::vector<std::size_t> targets = {1000, 250, 100, 25, 10};
    Vec3d c;
    double radius;
    mesh_ball<double>(mesh, c, radius);
    const std::size_t lines = o.quick ? 5000 : 40000;
    const double pm = mesh_hit_fraction<double>(mesh, c, radius, lines, 31);
    std::printf("\n== %s (%zu triangles): hit probability of isotropic random lines, mesh %.4f (%zu lines) ==\n",
                name.c_str(), mesh.size(), pm, lines);
    for (bool calibrate : {false, true}) {
        OccluderOptions opt;
        opt.calibrate = calibrate;
        const double t0 = now();
        const auto levels = generate_occluder_levels<double>(mesh, targets, opt);
        const double t = now() - t0;
        std::printf("%-26s generation %.2f s;", calibrate ? "D2+fitted GSSA+calibrated" : "D2+fitted GSSA (Szecsi)", t);
        for (std::size_t k = 0; k < targets.size(); ++k) {
            const double ps = sphere_set_hit_fraction<double>(levels[k], c, radius, lines, 31);
            std::printf("  %zu: %+.1f%%", targets[k], 100 * (ps / pm - 1));
        }
        std::printf("\n");
    }
}

Mesh<float> to_float(const Mesh<double>& m) {
    Mesh<float> out(m.size());
    for (std::size_t i = 0; i < m.size(); ++i)
        for (int k = 0; k < 3; ++k) out[i][std::size_t(k)] = Vec3f(m[i][std::size_t(k)]);
    return out;
}

/// Object scaled into the occluder box [-1, 1]^3 (tests/support/occluder_box.hpp), standing
/// on its floor.
Mesh<double> place_in_box(const Mesh<double>& object) {
    AABB<double> b = mesh_bounds<double>(object);
    const Vec3d e = b.extent();
    const double s = 1.3 / std::max({e.x, e.y, e.z});
    const Vec3d shift = Vec3d(0, -1 + 0.02 + 0.5 * s * e.y, -0.1) - s * b.center();
    Mesh<double> placed = object;
    for (auto& t : placed)
        for (auto& v : t) v = v * s + shift;
    return placed;
}

void render_scene(const std::string& name, const Mesh<double>& object, const Options& o, std::vector<CsvRow>& rows) {
    const Mesh<double> placed = place_in_box(object);
    const Mesh<float> placed_f = to_float(placed);
    const Scene<float> sc = occluder_box(placed_f, Rgb<float>(15.f, 14.f, 12.f), false);
    using Tree = MeshBvh<MollerTrumbore<float>, 8>;  // glint's fastest tree for the shadow rays
    const Tree tree(std::span<const TriangleVertices<float>>(sc.triangles), {.threads = 1});
    // The VPL integrator's indirect part, one camera ray per pixel centre, one thread.
    const int size = o.quick ? 32 : 128;
    const RenderSettings image{.width = size, .height = size, .spp = 1, .threads = 1, .pixel_jitter = false};
    const VplSettings st{.min_distance = 0.1, .direct = false};
    const std::size_t walks = o.quick ? 40 : 300;
    const auto vpls = shoot_scene_vpls(sc, tree, Roulette<float, 3>::spectral(), walks, 17);
    const std::span<const Vpl<float>> vs(vpls);
    const auto gather = [&](const auto& visibility) {
        return std::move(render_vpls(sc, tree, vs, visibility, image, st).image.pixels);
    };
    std::printf("\n== VPL render: %s in a box, %zu triangles, %dx%d pixels, %zu VPLs from %zu walks ==\n", name.c_str(),
                sc.triangles.size(), image.width, image.height, vpls.size(), walks);

    double t0 = now();
    const auto ref = gather(ShadowRayVisibility<Tree>(tree, 1e-4f));
    const double t_rays = now() - t0;
    rows.push_back({name, "rays", 0, t_rays, 0.0});
    std::printf("%-16s %8s %10s %10s %9s\n", "visibility", "spheres", "seconds", "speedup", "rel_rmse");
    std::printf("%-16s %8s %10.3f %10s %9s\n", "rays", "-", t_rays, "1.0", "0");

    std::vector<std::size_t> counts = {10, 25, 50, 100, 250, 500, 1000, 2000, 4000};
    if (o.quick) counts = {10, 100, 1000};
    const auto t_gen = now();
    const auto levels = generate_occluder_levels<double>(placed, counts);
    std::printf("(generation of all levels: %.2f s)\n", now() - t_gen);
    std::vector<Rgb<float>> img100;
    std::size_t crossover = 0;
    double best_speedup_ok = 0;
    std::size_t best_speedup_n = 0;
    for (std::size_t k = 0; k < counts.size(); ++k) {
        std::vector<Sphere<float>> sf;
        for (const auto& s : levels[k]) sf.push_back({Vec3f(s.centre), float(s.radius)});
        const SphereVisibilityLinear<float> lin(sf);
        const SphereVisibilityKdTree<float> kd(sf);
        t0 = now();
        const auto a = gather(lin);
        const double t_lin = now() - t0;
        t0 = now();
        const auto b = gather(kd);
        const double t_kd = now() - t0;
        const auto error = [&](const std::vector<Rgb<float>>& img) {
            return relative_rmse(std::span<const Rgb<float>>(img), std::span<const Rgb<float>>(ref));
        };
        const double e_lin = error(a), e_kd = error(b);
        rows.push_back({name, "spheres-linear", sf.size(), t_lin, e_lin});
        rows.push_back({name, "spheres-kdtree", sf.size(), t_kd, e_kd});
        std::printf("%-16s %8zu %10.3f %10.1f %9.4f\n", "spheres-linear", sf.size(), t_lin, t_rays / t_lin, e_lin);
        std::printf("%-16s %8zu %10.3f %10.1f %9.4f\n", "spheres-kdtree", sf.size(), t_kd, t_rays / t_kd, e_kd);
        if (!crossover && t_kd < t_lin) crossover = sf.size();
        if (sf.size() <= 100 && e_lin <= 0.05 && t_rays / t_lin > best_speedup_ok)
            best_speedup_ok = t_rays / t_lin, best_speedup_n = sf.size();
        if (counts[k] == 100) img100 = a;
    }
    if (best_speedup_n)
        std::printf("best speedup at rel_rmse <= 0.05 with <= 100 spheres: %.1fx (%zu spheres, linear scan)\n",
                    best_speedup_ok, best_speedup_n);
    else
        std::printf("no sphere set of <= 100 spheres reached rel_rmse <= 0.05\n");
    if (crossover)
        std::printf("kd-tree search first faster than the linear scan at %zu spheres\n", crossover);
    else
        std::printf("kd-tree search never faster than the linear scan up to %zu spheres\n", counts.back());
    // Side by side: rays | 100 spheres (linear) | 4x |difference|.
    if (!img100.empty() && !o.images.empty()) {
        double mean = 0;
        for (const auto& p : ref) mean += double(p.luminance());
        mean /= double(ref.size());
        const float scale = float(0.5 / std::max(mean, 1e-12));
        const int w = image.width, h = image.height;
        Image<Rgb<float>> side(3 * w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
                side.at(x, y) = ref[i] * scale;
                side.at(w + x, y) = img100[i] * scale;
                for (std::size_t c = 0; c < 3; ++c)
                    side.at(2 * w + x, y)[c] = 4.f * std::abs(img100[i][c] - ref[i][c]) * scale;
            }
        const std::string path = o.images + "/occluders_" + name + ".png";
        write_png(path, side);
        std::printf("wrote %s (shadow rays | 100 spheres | 4x difference)\n", path.c_str());
    }
}

int run(const Options& o) {
    std::vector<CsvRow> rows;
    delaunay_scaling(o);
    const auto knot = make_torus_knot<double>();
    hit_probability("torus-knot", knot, o);
    Mesh<double> mesh;
    std::string mesh_name;
    if (!o.mesh.empty()) {
        mesh = read_obj(o.mesh);
        mesh_name = o.mesh.substr(o.mesh.find_last_of('/') + 1);
        mesh_name = mesh_name.substr(0, mesh_name.find('.'));
        hit_probability(mesh_name, mesh, o);
    }
    if (!o.quick) {
        const auto big = make_torus_knot<double>(2500, 20);
        const double t0 = now();
        const auto s = generate_occluders<double>(big, 100);
        std::printf("\n100k-triangle mesh (%zu triangles): generation of 100 spheres %.2f s\n", big.size(), now() - t0);
    }
    render_scene("torus-knot", knot, o, rows);
    if (!mesh.empty()) render_scene(mesh_name, mesh, o, rows);
    if (!o.csv.empty()) {
        std::ofstream f(o.csv);
        if (!f) throw Error("cannot write " + o.csv);
        f << "scene,visibility,spheres,seconds,rel_rmse\n";
        for (const auto& r : rows)
            f << r.scene << ',' << r.visibility << ',' << r.spheres << ',' << r.seconds << ',' << r.rel_rmse << '\n';
        std::printf("\nwrote %s\n", o.csv.c_str());
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    try {
        cli::App app("bench_occluders: occluder spheres for VPL visibility (Szecsi 2009, ch. 5) against shadow rays");
        cli::flag(app, "--quick", o.quick, "a smoke run");
        cli::output(app, "--csv", o.csv, "write the rows as CSV");
        cli::text(app, "--mesh", o.mesh, "FILE.obj: the mesh row's occluder (default: the bunny)");
        cli::folder(app, "--images", o.images, "write the images into this folder");
        bool fit = false;
        cli::flag(app, "--fit-gssa", fit, "fit the GSSA model's constants and exit");
        if (!cli::parse(app, argc, argv)) return 0;
        if (fit) return fit_gssa(400000);
        return run(o);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_occluders: %s\n", e.what());
        return 1;
    }
}
