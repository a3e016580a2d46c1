// Tests for glint/tracer and glint/io: the furnace renders to 1, direct lighting from a fully
// visible polygon light equals the form factor, the Cornell box converges as 1/sqrt(spp),
// rendering is independent of the thread count, and files round-trip or fail clearly.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include <glint/io/exr.hpp>
#include <glint/io/obj.hpp>
#include <glint/io/obj_scene.hpp>
#define GLINT_STB_IMPLEMENTATION  // stb_image_write's functions, compiled in this file
#include <glint/io/png.hpp>
#include <glint/io/scene_json.hpp>
#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/correlated_environment.hpp>
#include <glint/tracer/first_hit_layers.hpp>
#include <glint/tracer/named_render.hpp>
#include "glint_instances.hpp"  // render_named for AnyAccel, compiled once (instances/)
#include <glint/tracer/scenes.hpp>
#include <glint/tracer/smooth_normals.hpp>
#include <glint/intersection/ivm.hpp>
#include <glint/trees/brute_force.hpp>


using namespace glint;

namespace {

RenderResult render_scene(const Scene<float>& s, NamedRender<float> o) {
    const DefaultAccel accel(s.triangles);
    return render_named(s, any_accel_view(accel), o);
}

/// Image mean per band and its standard error from the per-pixel variances of the means.
void image_mean(const RenderResult& r, Rgb<double>& mean, Rgb<double>& se) {
    const double n = double(r.image.size());
    mean = Rgb<double>(0.0);
    Rgb<double> var(0.0);
    for (std::size_t i = 0; i < r.image.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            mean[c] += r.image.pixels[i][c] / n;
            var[c] += r.variance.pixels[i][c] / (n * n);
        }
    for (std::size_t c = 0; c < 3; ++c) se[c] = std::sqrt(var[c]);
}

// Samples per pixel of the roulette agreement cases below: a quarter under the sanitizers
// (-DGLINT_SANITIZER_TESTS), whose instrumented walks run 10-25 times slower and are there for
// memory errors; the portable build's suites check the estimators at full size. Every
// tolerance comes from the run's own measured variance, so it holds at either size.
#if defined(GLINT_SANITIZER_TESTS)
constexpr int stat_spp = 64;
#else
constexpr int stat_spp = 256;
#endif

std::string temp_path(const std::string& name) {
    return (std::filesystem::temp_directory_path() / ("glint_test_" + name)).string();
}

}  // namespace

TEST_CASE("accuracy: the saturated furnace renders to 1 in every band, for every roulette") {
    // "none" (no roulette) is left out: its throughput cut-off drops light by design.
    const Scene<float> s = builtin_scene<float>("furnace");
    for (const std::string roulette : {"classic", "spectral", "estimate", "spectral+estimate", "throughput",
                                       "throughput+spectral", "throughput+estimate", "throughput+spectral+estimate"}) {
        for (const std::string direct : {"brdf", "mis"}) {
            NamedRender<float> o;
            o.image.width = o.image.height = 24;
            o.image.spp = stat_spp;
            o.image.threads = 2;
            o.roulette = roulette;
            o.direct = direct;
            const RenderResult r = render_scene(s, o);
            Rgb<double> mean, se;
            image_mean(r, mean, se);
            CAPTURE(roulette);
            CAPTURE(direct);
            // The image mean within 4 standard errors of 1 in each band (48 checks: all pass
            // at 4 SE with probability 0.997 for an unbiased renderer, fixed seeds)...
            for (std::size_t c = 0; c < 3; ++c) {
                CAPTURE(c);
                CAPTURE(mean[c]);
                CAPTURE(se[c]);
                CHECK(se[c] > 0.0);
                CHECK(std::abs(mean[c] - 1.0) < 4.0 * se[c]);
            }
            // ...and so is the mean over each region where a leak or bias would gather: the
            // border ring (edges and corners of the view) and the four quadrants, each within
            // 4 of its standard errors (from the summed per-pixel variances of the mean) in
            // every band. 4, not 3: 5 regions x 3 bands x 16 policy pairs = 240 checks, and a
            // normal estimate passes all of them at 4 SE with probability 0.985 (fixed seeds).
            const int w = r.image.width, h = r.image.height;
            const auto region_check = [&](const char* name, auto&& inside) {
                for (std::size_t c = 0; c < 3; ++c) {
                    double sum = 0, var = 0;
                    int n = 0;
                    for (int y = 0; y < h; ++y)
                        for (int x = 0; x < w; ++x)
                            if (inside(x, y)) {
                                sum += r.image.at(x, y)[c];
                                var += r.variance.at(x, y)[c];
                                ++n;
                            }
                    const double m = sum / n, region_se = std::sqrt(var) / n;
                    CAPTURE(name);
                    CAPTURE(c);
                    CAPTURE(m);
                    CAPTURE(region_se);
                    CHECK(region_se > 0.0);
                    CHECK(std::abs(m - 1.0) < 4.0 * region_se);
                }
            };
            region_check("border", [&](int x, int y) { return x == 0 || y == 0 || x == w - 1 || y == h - 1; });
            for (int q = 0; q < 4; ++q)
                region_check("quadrant", [&](int x, int y) { return (x < w / 2) == (q % 2 == 0) && (y < h / 2) == (q < 2); });
        }
    }
}

TEST_CASE("accuracy: every roulette agrees with classic on the open Cornell box") {
    // The furnace's answer is the same everywhere; here the radiance varies and light escapes,
    // so an estimate roulette's L~ (pilot-fitted or Szécsi 2009, §2.3's closed-scene formula, which
    // overestimates here) is far from L_in at most vertices. Unbiased roulettes still give the
    // same image mean: each band's difference to classic within 4 standard errors (the two
    // renders are independent; SE from their summed per-pixel variances of the mean).
    const Scene<float> s = builtin_scene<float>("cornell");
    const DefaultAccel accel(s.triangles);
    NamedRender<float> o;
    o.image.width = o.image.height = 24;
    o.image.spp = stat_spp;
    o.image.pixel_jitter = false;
    o.roulette = "classic";
    o.seed = 501;
    const RenderResult base = render_named(s, any_accel_view(accel), o);
    Rgb<double> base_mean, base_se;
    image_mean(base, base_mean, base_se);
    for (const std::string roulette : {"spectral", "estimate", "spectral+estimate", "throughput", "throughput+spectral",
                                       "throughput+estimate", "throughput+spectral+estimate"})
        for (const std::string estimate : {"pilot", "scene"}) {
            if (!roulette.ends_with("estimate") && estimate == "scene") continue;
            o.roulette = roulette;
            o.estimate = estimate;
            ++o.seed;
            const RenderResult r = render_named(s, any_accel_view(accel), o);
            Rgb<double> mean, se;
            image_mean(r, mean, se);
            for (std::size_t c = 0; c < 3; ++c) {
                CAPTURE(roulette);
                CAPTURE(estimate);
                CAPTURE(c);
                CAPTURE(mean[c]);
                CAPTURE(base_mean[c]);
                const double both = std::sqrt(se[c] * se[c] + base_se[c] * base_se[c]);
                CHECK(both > 0.0);
                CHECK(std::abs(mean[c] - base_mean[c]) < 4.0 * both);
            }
        }
}

TEST_CASE("grey scenes: the spectral roulettes render classic's image, colour or not in the lights") {
    // With every reflectance grey, Szécsi 2009, §2.2's spectral rule <F a, H> / <F, H> is the
    // albedo itself (test_sampling: spectral == classic for grey albedo), so roulette_choices
    // gives grey scenes the classic rules; the images are the same. The coloured Cornell box is not grey.
    Scene<float> s = builtin_scene<float>("cornell");
    CHECK_FALSE(s.features().grey);
    for (auto& m : s.materials) {
        m.kd = Rgb<float>(m.kd.luminance());
        m.ks = Rgb<float>(m.ks.luminance());
    }
    const SceneFeatures f = s.features();
    CHECK(f.grey);  // the light's emission (17, 12, 4) stays coloured
    const DefaultAccel accel(s.triangles);
    NamedRender<float> o;
    o.image.width = o.image.height = 16;
    o.image.spp = 8;
    for (const auto& names : {std::pair{"spectral", "classic"}, std::pair{"spectral+estimate", "estimate"}}) {
        const char* spectral = names.first;  // not a structured binding: clang 14 cannot capture one
        const char* classic = names.second;
        o.roulette = spectral;
        const RenderResult a = render_named(s, any_accel_view(accel), o);
        o.roulette = classic;
        const RenderResult b = render_named(s, any_accel_view(accel), o);
        CAPTURE(spectral);
        CHECK(a.image.pixels == b.image.pixels);
    }
}

TEST_CASE("accuracy: the furnace with the Halton sampler") {
    NamedRender<float> o;
    o.image.width = o.image.height = 16;
    o.image.spp = 64;
    o.sampler = "halton";
    o.direct = "brdf";
    const RenderResult r = render_scene(builtin_scene<float>("furnace"), o);
    Rgb<double> mean, se;
    image_mean(r, mean, se);
    for (std::size_t c = 0; c < 3; ++c) CHECK(std::abs(mean[c] - 1.0) < 3.0 * se[c]);
}

namespace {

/// The light's corners in formfactor_scene.
const std::array<Vec3f, 4> formfactor_light{Vec3f(0.2f, 1, -0.4f), Vec3f(1.2f, 1, -0.4f), Vec3f(1.2f, 1, 0.6f),
                                                Vec3f(0.2f, 1, 0.6f)};

/// A diffuse floor (albedo 0.5) under a 1 x 1 light (Le = 2) at height 1, offset so that the
/// geometry is not symmetric. With occluder_x1 > occluder_x0: a black quad at height 0.5 over
/// x in [x0, x1], z in [-0.5, 0.5], which hides from the origin the light's points with x in
/// [2 x0, 2 x1] (a shadow ray to (x, 1, z) crosses height 0.5 at (x/2, z/2)).
Scene<float> formfactor_scene(float occluder_x0 = 0, float occluder_x1 = 0) {
    Scene<float> s;
    s.name = "formfactor";
    const auto floor = s.add_material(Material<float>::lambertian(Rgb<float>(0.5f)));
    const auto light = s.add_material(Material<float>::lambertian(Rgb<float>(0.0f), Rgb<float>(2.0f)));
    s.add_quad(Vec3f(-5, 0, -5), Vec3f(-5, 0, 5), Vec3f(5, 0, 5), Vec3f(5, 0, -5), floor);
    s.add_polygon(formfactor_light, light);  // counter-clockwise seen from below: faces down
    if (occluder_x1 > occluder_x0) {
        const auto black = s.add_material(Material<float>::lambertian(Rgb<float>(0.0f)));
        s.add_quad(Vec3f(occluder_x0, 0.5f, -0.5f), Vec3f(occluder_x0, 0.5f, 0.5f), Vec3f(occluder_x1, 0.5f, 0.5f),
                   Vec3f(occluder_x1, 0.5f, -0.5f), black);
    }
    return s;
}

}  // namespace

TEST_CASE("accuracy: direct light from a fully visible polygon light equals the form factor") {
    // Outgoing radiance at x: rho Le F(x).
    const Scene<float> s = formfactor_scene();
    const auto& lq = formfactor_light;
    REQUIRE(s.area_lights.size() == 1);
    REQUIRE(s.area_lights[0].normal.y < 0);

    const Vec3f x(0, 0, 0), n(0, 1, 0);
    const double F = point_to_polygon_form_factor<double>(Vec3d(x), Vec3d(n),
        std::vector<Vec3d>{Vec3d(lq[0]), Vec3d(lq[1]), Vec3d(lq[2]), Vec3d(lq[3])});
    const double expected = 0.5 * 2.0 * F;
    CHECK(F > 0.05);

    const BruteForce<Ivm<float>> accel(s.triangles);
    const Ray<float> down{Vec3f(0, 0.5f, 0), Vec3f(0, -1, 0)};
    PathTracerSettings<float> settings{.roulette = Roulette<float, 3>::classic()};
    settings.max_depth = 1;  // the first vertex only: its direct light
    SUBCASE("light and BRDF sampling by MIS: unbiased within 4 standard errors") {
        // The BRDF sample of the MIS pair is the continuation ray: a second vertex (on the
        // light, which reflects nothing) is where its share of the direct light is counted.
        settings.max_depth = 2;
        PathTracer<BruteForce<Ivm<float>>, RandomSampler<float>, MisDirect<float>> pt(s, accel, settings);
        RandomSampler<float> sampler(1);
        double sum = 0, sum2 = 0;
        const int n_samples = 100000;
        for (int i = 0; i < n_samples; ++i) {
            sampler.start_pixel_sample(0, 0, std::uint64_t(i));
            const double L = pt.radiance(down, sampler).L[0];
            sum += L;
            sum2 += L * L;
        }
        const double mean = sum / n_samples, se = std::sqrt((sum2 / n_samples - mean * mean) / n_samples);
        CAPTURE(mean);
        CAPTURE(expected);
        CHECK(std::abs(mean - expected) < 4 * se);
    }
    SUBCASE("combined correlated sampling: exact, zero variance, lambda = 1") {
        settings.light_samples = 10;
        using Tracer = PathTracer<BruteForce<Ivm<float>>, RandomSampler<float>, CorrelatedDirect<float>>;
        RandomSampler<float> sampler(2);
        // lambda per vertex: the combined estimate is part of the walk's radiance.
        settings.lambda_filter_radius = -1;
        const Tracer pt(s, accel, CorrelatedDirect<float>(s, settings, DirectEstimator::combined), MisEnvironment<float>(s),
                        settings);
        Tracer::pixel_state state;
        for (int i = 0; i < 100; ++i) {
            sampler.start_pixel_sample(0, 0, std::uint64_t(i));
            const Rgb<float> L = pt.radiance(down, sampler, state).L;
            CHECK(L[0] == doctest::Approx(expected).epsilon(1e-4));
        }
        REQUIRE(state.lambda_count == 100);
        CHECK(state.lambda_sum / 100.0 == doctest::Approx(1.0).epsilon(1e-4));
        // lambda pooled over pixels (radius 1, the default): the primary vertex's parts are kept
        // in the pixel's statistics, and finish() forms the pixel once (Szécsi 2009, §3.1.1).
        settings.lambda_filter_radius = 1;
        const Tracer pooled(s, accel, settings);
        std::vector<Tracer::pixel_state> states(1);
        for (int i = 0; i < 100; ++i) {
            sampler.start_pixel_sample(0, 0, std::uint64_t(i));
            CHECK(pooled.radiance(down, sampler, states[0]).L[0] == 0.0f);
        }
        Film film;
        film.resize(1, 1);
        pooled.finish(film, std::span<const Tracer::pixel_state>(states));
        CHECK(film.image.at(0, 0)[0] == doctest::Approx(expected).epsilon(1e-4));
        CHECK(film.variance.at(0, 0)[0] <= 1e-6 * expected * expected);
        REQUIRE(film.layer("lambda"));
        CHECK(film.layer("lambda")->pixels.at(0, 0)[0] == doctest::Approx(1.0f).epsilon(1e-4));
    }
}

TEST_CASE("lambda = fractional visibility (Szécsi 2009, §3.2): the visible share of the light, exact at 0 and 1") {
    // The origin of formfactor_scene, seen by a ray straight down; 10 light samples per vertex,
    // lambda per vertex (radius -1).
    const Ray<float> down{Vec3f(0, 0.5f, 0), Vec3f(0, -1, 0)};
    PathTracerSettings<float> settings{.roulette = Roulette<float, 3>::classic()};
    settings.max_depth = 1;  // the first vertex only: its direct light
    settings.light_samples = 10;
    settings.lambda_filter_radius = -1;
    using Tracer = PathTracer<BruteForce<Ivm<float>>, RandomSampler<float>, CorrelatedDirect<float>>;
    auto tracer = [&](const Scene<float>& s, const BruteForce<Ivm<float>>& accel, const PathTracerSettings<float>& st) {
        return Tracer(s, accel, CorrelatedDirect<float>(s, st, DirectEstimator::combined, LambdaSource::visibility),
                      MisEnvironment<float>(s), st);
    };
    const double exact = 0.5 * 2.0 * point_to_polygon_form_factor<double>(Vec3d(0), Vec3d(0, 1, 0),
        std::vector<Vec3d>{Vec3d(formfactor_light[0]), Vec3d(formfactor_light[1]), Vec3d(formfactor_light[2]),
                           Vec3d(formfactor_light[3])});
    SUBCASE("fully visible: lambda = 1, the form factor's answer; fully hidden: lambda = 0, zero") {
        for (const bool hidden : {false, true}) {
            // The hiding occluder covers x in [0.05, 0.65]: the light's x in [0.1, 1.3].
            const Scene<float> s = hidden ? formfactor_scene(0.05f, 0.65f) : formfactor_scene();
            const BruteForce<Ivm<float>> accel(s.triangles);
            const Tracer pt = tracer(s, accel, settings);
            RandomSampler<float> sampler(3);
            Tracer::pixel_state state;
            for (int i = 0; i < 50; ++i) {
                sampler.start_pixel_sample(0, 0, std::uint64_t(i));
                const float L = pt.radiance(down, sampler, state).L[0];
                if (hidden) CHECK(L == 0.0f);
                else CHECK(L == doctest::Approx(exact).epsilon(1e-4));
            }
            CHECK(state.lambda_sum == (hidden ? 0.0 : 50.0));
            CHECK(state.traced == 500.0);
        }
    }
    SUBCASE("half hidden: E[lambda] = 1/2 within 4 measured standard errors; pooled lambda = the mean share") {
        // The occluder over x in [0.1, 0.35] hides the light's x in [0.2, 0.7]: half its area,
        // and the light's points are uniform in area.
        const Scene<float> s = formfactor_scene(0.1f, 0.35f);
        const BruteForce<Ivm<float>> accel(s.triangles);
        const Tracer pt = tracer(s, accel, settings);
        RandomSampler<float> sampler(4);
        const int n = 4000;
        double sum = 0, sum2 = 0;
        for (int i = 0; i < n; ++i) {
            sampler.start_pixel_sample(0, 0, std::uint64_t(i));
            Tracer::pixel_state state;
            pt.radiance(down, sampler, state);
            REQUIRE(state.lambda_count == 1);
            sum += state.lambda_sum;
            sum2 += state.lambda_sum * state.lambda_sum;
        }
        const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
        CAPTURE(mean);
        CAPTURE(se);
        CHECK(se > 0.0);
        CHECK(std::abs(mean - 0.5) < 4.0 * se);
        // Pooled at radius 0 over the same samples: the film's lambda is the share of all the
        // pixel's shadow rays that reached the light, here the mean of the per-vertex shares.
        PathTracerSettings<float> pooled_settings = settings;
        pooled_settings.lambda_filter_radius = 0;
        const Tracer pooled = tracer(s, accel, pooled_settings);
        std::vector<Tracer::pixel_state> states(1);
        for (int i = 0; i < n; ++i) {
            sampler.start_pixel_sample(0, 0, std::uint64_t(i));
            pooled.radiance(down, sampler, states[0]);
        }
        Film film;
        film.resize(1, 1);
        pooled.finish(film, std::span<const Tracer::pixel_state>(states));
        REQUIRE(film.layer("lambda"));
        CHECK(film.layer("lambda")->pixels.at(0, 0)[0] == doctest::Approx(mean).epsilon(1e-5));
    }
}

namespace {

/// A direct-lighting policy written here, outside the library: next-event estimation only,
/// one point uniform on each area light per vertex, no MIS (emission the BRDF sample meets
/// counts 0, since the light samples estimate the lights whole). It keeps no per-pixel
/// statistics. Unbiased, as MisDirect is, with another variance.
struct UniformAreaDirect : NoPixelStatistics<float> {
    explicit UniformAreaDirect(const Scene<float>& scene) : lights(scene) {}

    template <class Q, class S>
    Rgb<float> estimate(const ShadingPoint<float>& sp, S& sampler, Q& queries, vertex_record*) const {
        Rgb<float> L(0.0f);
        for (const auto& light : lights.lights()) {
            const Vec3f y = light.sampler().sample(sampler.get_2d());
            const float G = light.geometry(sp.x, sp.n, y) * light.sampler().area();  // G / p
            if (G > 0.0f && queries.visible(sp, light, y))
                L += light.radiance() * sp.brdf->f(sp.frame.to_local(safe_normalize(y - sp.x))) * G;
        }
        return L;
    }
    float emission_weight(const Arrival<float>& from, const Ray<float>&, const StoreHit<float>&) const {
        return from.lights_sampled ? 0.0f : 1.0f;
    }

    SceneLights<float> lights;
};

}  // namespace

namespace {

/// The envmap scene's image (full paths) with environment policy `env`, camera rays through
/// pixel centres.
template <class E>
RenderResult render_envmap(const Scene<float>& s, const DefaultAccel& accel, const E& env, int size, int spp,
                           std::uint64_t seed) {
    RenderSettings image;
    image.width = image.height = size;
    image.spp = spp;
    image.pixel_jitter = false;
    const PathTracerSettings<float> settings{.roulette = Roulette<float, 3>::spectral()};
    const PathTracer<DefaultAccel, RandomSampler<float>, MisDirect<float>, E> pt(s, accel, MisDirect<float>(s, settings), env,
                                                                                  settings);
    return render_image(s, image, pt, RandomSampler<float>(seed));
}

/// A shading point with normal n on material m, seen from direction `view` (towards the eye).
struct EnvVertex {
    Frame<float> frame;
    SurfaceBrdf<float> brdf;
    ShadingPoint<float> sp;
    EnvVertex(const Material<float>& m, const Vec3f& n, const Vec3f& view)
        : frame(Frame<float>::from_normal(n)), brdf(m, frame.to_local(view)),
          sp{Vec3f(0.0f), Vec3f(0.0f), n, n, frame, &brdf} {}
};

}  // namespace

TEST_CASE("statistics: correlated environment lighting (Szécsi 2009, §3.3) renders MisEnvironment's image mean") {
    // envmap, 12x12, full paths: importance (lambda = 0), correlated (lambda = 1, eq. 3.5 only)
    // and combined (both main parts chosen per cell, leave-one-out lambda) against the map's
    // MIS, per band within 4 standard errors of the difference (from the variance layers).
    const Scene<float> s = builtin_scene<float>("envmap");
    const DefaultAccel accel(s.triangles);
    Rgb<double> mis_mean, mis_se;
    image_mean(render_envmap(s, accel, MisEnvironment<float>(s), 12, 256, 1), mis_mean, mis_se);
    for (const DirectEstimator e : {DirectEstimator::importance, DirectEstimator::correlated, DirectEstimator::combined}) {
        CorrelatedEnvironmentSettings cs;
        cs.estimator = e;
        if (e == DirectEstimator::correlated) cs.main_part = EnvironmentMainPart::radiance;
        Rgb<double> mean, se;
        image_mean(render_envmap(s, accel, CorrelatedEnvironment<float>(s, cs), 12, 64, 2), mean, se);
        for (std::size_t c = 0; c < 3; ++c) {
            INFO("estimator " << int(e) << " band " << c << ": " << mean[c] << " +- " << se[c] << ", MIS " << mis_mean[c]
                              << " +- " << mis_se[c]);
            CHECK(std::abs(mean[c] - mis_mean[c]) < 4 * std::sqrt(se[c] * se[c] + mis_se[c] * mis_se[c]));
            CHECK(se[c] > 0.0);
        }
    }
}

TEST_CASE("CorrelatedEnvironment: the main part chosen per cell, and J the integral of the chosen parts") {
    const Scene<float> s = builtin_scene<float>("envmap");
    const CorrelatedEnvironment<float> env(s);
    using Part = CorrelatedEnvironment<float>::CellPart;
    const auto& cells = env.cells();
    auto to_cells = [](const Vec3f& w) { return Vec3f(w.x, w.z, w.y); };  // the map's up axis is the cells' pole
    const Vec3f sun = glm::normalize(Vec3f(0.5f, 0.6f, 0.3f));            // default_sky's sun
    for (const Vec3f n : {Vec3f(0, 1, 0), glm::normalize(Vec3f(0.6f, 0.3f, 0.74f))}) {
        EnvVertex v(s.materials[1], n, glm::normalize(Vec3f(0.2f, 0.5f, 0.8f) + n));
        std::vector<Part> parts(cells.count());
        const Rgb<float> J = env.main_parts(v.sp, parts);
        int radiance = 0, brdf = 0;
        for (std::size_t d = 0; d < parts.size(); ++d) {
            if (parts[d].part == EnvironmentMainPart::brdf) {
                ++brdf;
                CHECK(cells.min_cosine(d, to_cells(n)) >= 0.0f);  // eq. 3.6's J is exact only there
            } else if (parts[d].weight.max() > 0.0f) {
                ++radiance;
            }
        }
        // Both main parts are in use, and the sun's cell (radiance varying most) keeps eq. 3.5.
        CHECK(radiance > 0);
        CHECK(brdf > 0);
        CHECK(parts[cells.cell_of(to_cells(sun))].part == EnvironmentMainPart::radiance);
        // J against Monte Carlo of g / p with the map's importance samples.
        Pcg32 rng(7);
        std::array<double, 3> sum{}, square{};
        const int m = 400000;
        for (int i = 0; i < m; ++i) {
            float pdf;
            const Vec3f w = s.environment->sample(Vec2<float>(rng.uniform<float>(), rng.uniform<float>()), pdf);
            const Part& p = parts[cells.cell_of(to_cells(w))];
            const Rgb<float> g = p.part == EnvironmentMainPart::radiance ? s.environment->eval(w) * p.weight / pdf
                                                                         : p.weight * (glm::dot(n, w) / pdf);
            for (std::size_t c = 0; c < 3; ++c) sum[c] += g[c], square[c] += double(g[c]) * g[c];
        }
        for (std::size_t c = 0; c < 3; ++c) {
            const double mean = sum[c] / m, se = std::sqrt((square[c] / m - mean * mean) / m);
            INFO("n (" << n.x << ", " << n.y << ", " << n.z << ") band " << c << ": J " << J[c] << ", Monte Carlo " << mean
                       << " +- " << se);
            CHECK(std::abs(J[c] - mean) < 4 * se);
        }
    }
    // One main part forced: eq. 3.6 wherever the cell lies above the tangent plane.
    CorrelatedEnvironmentSettings cs;
    cs.main_part = EnvironmentMainPart::brdf;
    const CorrelatedEnvironment<float> forced(s, cs);
    EnvVertex v(s.materials[0], Vec3f(0, 1, 0), Vec3f(0, 1, 0));
    std::vector<Part> parts(cells.count());
    forced.main_parts(v.sp, parts);
    for (std::size_t d = 0; d < parts.size(); ++d)
        CHECK((parts[d].part == EnvironmentMainPart::brdf) == (cells.min_cosine(d, Vec3f(0, 0, 1)) >= 0.0f));
    CHECK_THROWS_AS(CorrelatedEnvironment<float>(s, CorrelatedEnvironmentSettings{16, 16, 16, DirectEstimator::combined, std::nullopt}), Error);
}

TEST_CASE("policies: a direct-lighting policy defined outside the library renders what MisDirect renders") {
    const Scene<float> s = builtin_scene<float>("cornell");
    REQUIRE(!s.features().environment);
    REQUIRE(!s.features().point_lights);
    const DefaultAccel accel(s.triangles);
    RenderSettings settings;
    settings.width = settings.height = 24;
    settings.spp = 128;
    settings.threads = 2;
    const PathTracerSettings<float> tracing{.roulette = Roulette<float, 3>::classic()};
    static_assert(DirectLighting<UniformAreaDirect, float, RayQueries<DefaultAccel>, RandomSampler<float>>);
    const PathTracer<DefaultAccel, RandomSampler<float>, UniformAreaDirect> own(s, accel, UniformAreaDirect(s),
                                                                                MisEnvironment<float>(s), tracing);
    const PathTracer<DefaultAccel, RandomSampler<float>, MisDirect<float>> mis(s, accel, tracing);
    const RenderResult a = render_image(s, settings, own, RandomSampler<float>(11));
    const RenderResult b = render_image(s, settings, mis, RandomSampler<float>(12));
    CHECK(a.rays > 0);
    // The image means per band agree within 4 standard errors (from the variance layers).
    Rgb<double> ma, sa, mb, sb;
    image_mean(a, ma, sa);
    image_mean(b, mb, sb);
    for (std::size_t c = 0; c < 3; ++c) {
        const double z = (ma[c] - mb[c]) / std::sqrt(sa[c] * sa[c] + sb[c] * sb[c]);
        CAPTURE(c);
        CAPTURE(ma[c]);
        CAPTURE(mb[c]);
        CHECK(ma[c] > 0.01);
        CHECK(std::abs(z) < 4.0);
    }
    // Per pixel: few pixels more than 4 standard errors apart (for Gaussian errors 0.006%;
    // heavy-tailed pixels with underestimated variances make some more).
    int far = 0, counted = 0;
    for (std::size_t i = 0; i < a.image.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            const double v = double(a.variance.pixels[i][c]) + double(b.variance.pixels[i][c]);
            if (!(v > 0.0)) continue;
            ++counted;
            far += std::abs(double(a.image.pixels[i][c]) - double(b.image.pixels[i][c])) / std::sqrt(v) > 4.0 ? 1 : 0;
        }
    CAPTURE(far);
    CHECK(counted > 1000);
    CHECK(far <= counted / 100);
}

namespace {

/// A film of one's own, outside include/ (a FilmPolicy): it keeps each pixel's luminance and
/// its standard error, and counts how often each pixel is written.
struct LuminanceFilm {
    int width = 0, height = 0;
    std::vector<float> luminance, standard_error;
    std::vector<int> writes;

    void resize(int w, int h) {
        width = w, height = h;
        luminance.assign(std::size_t(w) * std::size_t(h), -1.0f);
        standard_error.assign(luminance.size(), -1.0f);
        writes.assign(luminance.size(), 0);
    }
    void set_pixel(int x, int y, const Rgb<float>& mean, const Rgb<float>& variance_of_mean) {
        const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
        luminance[i] = mean.luminance();
        standard_error[i] = std::sqrt(variance_of_mean.luminance());
        ++writes[i];
    }
};

}  // namespace

TEST_CASE("policies: a film defined outside the library receives exactly the pixels of the default film") {
    const Scene<float> s = builtin_scene<float>("cornell");
    const DefaultAccel accel(s.triangles);
    RenderSettings settings;
    settings.width = 20, settings.height = 12;  // not a multiple of the 16-pixel tiles
    settings.spp = 8;
    settings.threads = 2;
    const PathTracer<DefaultAccel, RandomSampler<float>, MisDirect<float>> tracer(
        s, accel, {.roulette = Roulette<float, 3>::classic()});
    static_assert(FilmPolicy<LuminanceFilm, float>);
    const RenderResult reference = render_image(s, settings, tracer, RandomSampler<float>(5));
    LuminanceFilm film;
    const RenderStats stats = render_image(s, settings, tracer, RandomSampler<float>(5), film);
    REQUIRE(film.luminance.size() == reference.image.size());
    CHECK(stats.paths == reference.paths);
    CHECK(stats.rays == reference.rays);
    int once = 0, equal = 0, lit = 0;
    for (std::size_t i = 0; i < film.luminance.size(); ++i) {
        once += film.writes[i] == 1;
        equal += film.luminance[i] == reference.image.pixels[i].luminance() &&
                 film.standard_error[i] == std::sqrt(reference.variance.pixels[i].luminance());
        lit += film.luminance[i] > 0.0f;
    }
    CHECK(once == int(film.luminance.size()));
    CHECK(equal == int(film.luminance.size()));
    CHECK(lit > int(film.luminance.size()) / 2);
}

namespace {

/// Integrator I with its first_hits() hidden: the renderer traces its camera rays one at a time.
template <class I>
struct OneRayAtATime {
    using scalar_type = typename I::scalar_type;
    using pixel_state = typename I::pixel_state;
    const I& in;
    template <class S>
    PathSample<scalar_type> radiance(const Ray<scalar_type>& ray, S& sampler, pixel_state& state) const {
        return in.radiance(ray, sampler, state);
    }
    template <class F>
    void finish(F& film, std::span<const pixel_state> states) const {
        in.finish(film, states);
    }
};

/// Renders `scene` with tracer type PT over `accel` both ways and checks the images are the same.
template <class PT, class S, class A>
void check_streamed_camera_rays(const Scene<float>& scene, const A& accel, const S& sampler) {
    const PT tracer(scene, accel, {.roulette = Roulette<float, 3>::classic()});
    static_assert(FirstHitIntegrator<PT, S>);
    static_assert(!FirstHitIntegrator<OneRayAtATime<PT>, S>);
    RenderSettings settings;
    settings.width = 37, settings.height = 21;  // partial tiles and partial 4 x 4 blocks
    settings.spp = 3;
    settings.threads = 2;
    const RenderResult streamed = render_image(scene, settings, tracer, sampler);
    const RenderResult single = render_image(scene, settings, OneRayAtATime<PT>{tracer}, sampler);
    CAPTURE(scene.name);
    CHECK(streamed.rays == single.rays);
    CHECK(streamed.rays > streamed.paths);
    CHECK(streamed.image.pixels == single.image.pixels);
    CHECK(streamed.variance.pixels == single.variance.pixels);
}

}  // namespace

TEST_CASE("renderer: camera rays traced as a tile's stream (16-ray packets) render the image of one ray at a time") {
    for (const char* name : {"cornell", "cornell-caustics", "envmap"}) {
        const Scene<float> s = builtin_scene<float>(name);
        const DefaultAccel bvh(s.triangles);
        check_streamed_camera_rays<PathTracer<DefaultAccel, RandomSampler<float>, MisDirect<float>>>(s, bvh, RandomSampler<float>(7));
        check_streamed_camera_rays<PathTracer<DefaultAccel, HaltonSampler<float>, MisDirect<float>>>(s, bvh, HaltonSampler<float>(37, 21, 16, HaltonRandomization::owen, 7));
        // Behind AnyAccel (one virtual call per stream), as render_named() traces.
        const auto any = any_accel_view(bvh);
        check_streamed_camera_rays<PathTracer<AnyAccel, RandomSampler<float>, MisDirect<float>>>(s, static_cast<const AnyAccel&>(any),
                                                                                               RandomSampler<float>(9));
        // An accelerator without streams: one ray at a time inside first_hits().
        const BruteForce<MollerTrumbore<float>> brute(s.triangles);
        check_streamed_camera_rays<PathTracer<BruteForce<MollerTrumbore<float>>, RandomSampler<float>, MisDirect<float>>>(
            s, brute, RandomSampler<float>(3));
    }
}

TEST_CASE("convergence: the Cornell box's RMSE falls as 1/sqrt(spp)") {
    const Scene<float> s = builtin_scene<float>("cornell");
    const DefaultAccel accel(s.triangles);
    NamedRender<float> o;
    o.image.width = o.image.height = 20;
    o.image.spp = 4096;
    o.seed = 1000;
    o.sampler = "random";  // Monte Carlo's rate (Halton walks converge faster at first)
    const RenderResult ref = render_named(s, any_accel_view(accel), o);
    double ref_var = 0;  // the reference's own error, subtracted from the measured MSE
    for (const auto& v : ref.variance.pixels) ref_var += double(v[0] + v[1] + v[2]) / (3.0 * double(ref.image.size()));
    std::vector<double> log_spp, log_rmse;
    for (int spp : {4, 16, 64}) {
        o.image.spp = spp;
        o.seed = std::uint64_t(spp);
        const RenderResult r = render_named(s, any_accel_view(accel), o);
        double mse = 0;
        for (std::size_t i = 0; i < r.image.size(); ++i)
            for (std::size_t c = 0; c < 3; ++c) {
                const double d = double(r.image.pixels[i][c]) - double(ref.image.pixels[i][c]);
                mse += d * d / (3.0 * double(r.image.size()));
            }
        log_spp.push_back(std::log(double(spp)));
        log_rmse.push_back(0.5 * std::log(mse - ref_var));
    }
    // Least-squares slope of log RMSE against log spp.
    double mx = 0, my = 0;
    for (std::size_t i = 0; i < 3; ++i) mx += log_spp[i] / 3, my += log_rmse[i] / 3;
    double sxy = 0, sxx = 0;
    for (std::size_t i = 0; i < 3; ++i) sxy += (log_spp[i] - mx) * (log_rmse[i] - my), sxx += (log_spp[i] - mx) * (log_spp[i] - mx);
    const double slope = sxy / sxx;
    std::printf("  cornell 20x20: RMSE slope %.3f (expected -0.5)\n", slope);
    CHECK(slope == doctest::Approx(-0.5).epsilon(0.2));
}

TEST_CASE("determinism: the image does not depend on the thread count") {
    const Scene<float> s = builtin_scene<float>("cornell");
    const DefaultAccel accel(s.triangles);
    NamedRender<float> o;
    o.image.width = o.image.height = 24;
    o.image.spp = 4;
    o.image.threads = 1;
    const RenderResult a = render_named(s, any_accel_view(accel), o);
    o.image.threads = 3;
    const RenderResult b = render_named(s, any_accel_view(accel), o);
    CHECK(a.image.pixels == b.image.pixels);
}

TEST_CASE("pixel_jitter off: every sample of a pixel follows the ray through its centre") {
    // Emission seen directly (max depth 1, no light sampling) is then the same for every
    // sample: zero variance in every pixel, the light's pixels exactly its emission. With
    // jitter, the pixels on the light's edges see it some of the time.
    const Scene<float> s = builtin_scene<float>("cornell");
    NamedRender<float> o;
    o.image.width = o.image.height = 32;
    o.image.spp = 8;
    o.tracer.max_depth = 1;
    o.direct = "brdf";
    o.image.pixel_jitter = false;
    const RenderResult centres = render_scene(s, o);
    o.image.pixel_jitter = true;
    const RenderResult jittered = render_scene(s, o);
    int light_pixels = 0, noisy_centres = 0, noisy_jittered = 0;
    for (std::size_t i = 0; i < centres.image.size(); ++i) {
        noisy_centres += centres.variance.pixels[i].max() > 0.0f;
        noisy_jittered += jittered.variance.pixels[i].max() > 0.0f;
        light_pixels += centres.image.pixels[i] == Rgb<float>(17.0f, 12.0f, 4.0f);
    }
    CHECK(noisy_centres == 0);
    CHECK(light_pixels > 0);
    CHECK(noisy_jittered > 0);
}

TEST_CASE("renderer: a host's executor runs the workers and a progress callback sees every tile; the image does not change") {
    const Scene<float> s = builtin_scene<float>("cornell");
    NamedRender<float> o;
    o.image.width = 40;
    o.image.height = 24;  // 3 x 2 tiles of 16 x 16
    o.image.spp = 2;
    o.image.threads = 3;
    const RenderResult own = render_scene(s, o);
    int calls = 0, workers = 0;
    o.image.executor = [&](int n, const std::function<void(int)>& task) {  // the host's pool: its own threads
        ++calls;
        workers = n;
        std::vector<std::thread> pool;
        for (int i = 0; i < n; ++i) pool.emplace_back([&task, i] { task(i); });
        for (auto& t : pool) t.join();
    };
    std::vector<RenderProgress> seen;
    o.image.progress = [&](const RenderProgress& p) { seen.push_back(p); };  // never two calls at once
    const RenderResult hosted = render_scene(s, o);
    CHECK(calls == 1);
    CHECK(workers == 3);
    REQUIRE(seen.size() == 6);
    for (std::size_t i = 0; i < seen.size(); ++i) {
        CHECK(seen[i].tiles == 6);
        CHECK(seen[i].tiles_done == int(i) + 1);
        if (i > 0) CHECK(seen[i].seconds >= seen[i - 1].seconds);
    }
    o.image.executor = [](int n, const std::function<void(int)>& task) {  // one task after another
        for (int i = 0; i < n; ++i) task(i);
    };
    o.image.progress = nullptr;
    const RenderResult serial = render_scene(s, o);
    CHECK(hosted.image.pixels == own.image.pixels);
    CHECK(serial.image.pixels == own.image.pixels);
    CHECK(hosted.rays == own.rays);
}

TEST_CASE("the named LIE and sparse policies sample the view of the image they render (its aspect, not a square)") {
    const Scene<float> s = builtin_scene<float>("lie-hall");
    RenderSettings image;
    image.width = 64;
    image.height = 32;
    const PathTracerSettings<float> ts;
    const DefaultAccel accel(s.triangles);
    for (const char* name : {"lie", "lie-mask", "sparse-interp", "sparse-recon"}) {
        CAPTURE(name);
        const DirectChoice<float> d =
            find_choice(direct_choices<float>(), "direct lighting", name).make(s, any_accel_view(accel), ts, image);
        REQUIRE(std::holds_alternative<ManyLightDirect<float>>(d));
        const auto& system = std::get<ManyLightDirect<float>>(d).system();
        if (const auto* lie = std::get_if<LieDirect<float>>(&system)) CHECK(lie->lie().settings().aspect == 2.0);
        else if (const auto* sparse = std::get_if<SparseDirect<float>>(&system)) CHECK(sparse->settings().aspect == 2.0);
        else FAIL("not a LIE or sparse policy");
    }
}

TEST_CASE("every built-in scene renders finite, non-negative images with every direct policy") {
    for (const auto& name : builtin_scene_names()) {
        const Scene<float> s = builtin_scene<float>(name);
        for (const auto& choice : direct_choices<float>()) {
            const std::string direct(choice.name);
            NamedRender<float> o;
            o.image.width = o.image.height = 8;
            o.image.spp = 2;
            o.direct = direct;
            const RenderResult r = render_scene(s, o);
            // Correlated sampling (a control variate) may give negative estimates in a pixel;
            // the other estimators may not.
            const bool may_be_negative = direct == "correlated" || direct == "combined";
            bool ok = true;
            for (const auto& p : r.image.pixels) ok &= p.is_finite() && (may_be_negative || p.min() >= 0.0f);
            CAPTURE(name);
            CAPTURE(direct);
            CHECK(ok);
            CHECK(r.rays > 0);
        }
    }
    CHECK_THROWS_AS(builtin_scene<float>("nosuchscene"), Error);
    NamedRender<float> bad;
    bad.roulette = "nosuch";
    CHECK_THROWS_AS(render_scene(builtin_scene<float>("cornell"), bad), Error);
}

TEST_CASE("io: EXR round trip with layers, PNG preview, and clear errors") {
    Image<Rgb<float>> img(5, 3);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x) img.at(x, y) = Rgb<float>(float(x), float(y), 0.25f * float(x + y));
    const std::string exr = temp_path("roundtrip.exr");
    // Layers with distinct values per pixel and channel, so a wrong stride or offset shows.
    std::vector<float> lambda(15), var(45);
    for (std::size_t i = 0; i < lambda.size(); ++i) lambda[i] = 0.1f * float(i) - 0.3f;
    for (std::size_t i = 0; i < var.size(); ++i) var[i] = 1.0f + 0.01f * float(i);
    write_exr(exr, img, {ExrLayer{"lambda", {"Y"}, lambda}, ExrLayer{"variance", {"R", "G", "B"}, var}});
    const Image<Rgb<float>> back = read_exr_rgb(exr);
    CHECK(back.width == 5);
    CHECK(back.height == 3);
    CHECK(back.pixels == img.pixels);
    {
        Imf::InputFile file(exr.c_str());
        std::vector<float> lambda_back(15, -1.0f), var_back(45, -1.0f);
        Imf::FrameBuffer fb;
        fb.insert("lambda.Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(lambda_back.data()), sizeof(float),
                                         5 * sizeof(float)));
        const char* rgb[3] = {"R", "G", "B"};
        for (int c = 0; c < 3; ++c)
            fb.insert(std::string("variance.") + rgb[c],
                      Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(var_back.data() + c), 3 * sizeof(float),
                                 15 * sizeof(float)));
        file.setFrameBuffer(fb);
        file.readPixels(0, 2);
        CHECK(lambda_back == lambda);
        CHECK(var_back == var);
    }
    CHECK_THROWS_AS(write_exr(exr, img, {ExrLayer{"bad", {"Y"}, std::vector<float>(3, 0.0f)}}), Error);
    CHECK_THROWS_AS(read_exr_rgb(temp_path("does_not_exist.exr")), Error);
    const std::string png = temp_path("preview.png");
    write_png(png, img);
    {
        // Decoded back, every byte is the clamped value through the sRGB curve.
        int w = 0, h = 0, n = 0;
        unsigned char* px = stbi_load(png.c_str(), &w, &h, &n, 3);
        REQUIRE(px != nullptr);
        CHECK(w == 5);
        CHECK(h == 3);
        int wrong = 0;
        for (std::size_t i = 0; i < img.size(); ++i)
            for (std::size_t c = 0; c < 3; ++c) wrong += px[3 * i + c] != to_srgb8(img.pixels[i][c]);
        stbi_image_free(px);
        CHECK(wrong == 0);
    }
    std::filesystem::remove(exr);
    std::filesystem::remove(png);
}

TEST_CASE("io: an EXR header declaring a huge image is rejected before allocation") {
    // A valid 2x2 file whose data window is patched to declare a huge image, padded so that
    // OpenEXR's offset table reads (2.7 kB), as a crafted file would be.
    const std::string path = temp_path("huge.exr");
    auto craft = [&](std::int32_t w, std::int32_t h) {
        write_exr(path, Image<Rgb<float>>(2, 2));
        std::string bytes;
        {
            std::ifstream in(path, std::ios::binary);
            bytes.assign(std::istreambuf_iterator<char>(in), {});
        }
        const std::string key("dataWindow\0box2i\0", 17);
        const auto at = bytes.find(key);
        REQUIRE(at != std::string::npos);
        const std::int32_t box[4] = {0, 0, w - 1, h - 1};
        std::memcpy(bytes.data() + at + key.size() + 4, box, sizeof box);  // after the 4-byte size
        bytes.append(2400, '\0');
        std::ofstream(path, std::ios::binary) << bytes;
    };
    auto message = [&](const ExrLimits& limits) -> std::string {
        try {
            read_exr_rgb(path, limits);
        } catch (const Error& e) {
            return e.what();
        }
        return "no error";
    };
    craft(1966088, 769);  // 1.5e9 pixels, 18 GB as RGB float: above max_pixels
    std::string msg = message({});
    CAPTURE(msg);
    CHECK(msg.find("declares 1966088 x 769 pixels") != std::string::npos);
    CHECK(msg.find("max_pixels") != std::string::npos);
    craft(4000, 4000);  // below max_pixels, but 192 MB of samples in a 2.7 kB file
    msg = message({});
    CHECK(msg.find("declares 4000 x 4000 pixels") != std::string::npos);
    CHECK(msg.find("can hold") != std::string::npos);
    // An honest file reads; the absolute limit applies to it too.
    write_exr(path, Image<Rgb<float>>(64, 64));
    CHECK(read_exr_rgb(path).width == 64);
    ExrLimits small;
    small.max_pixels = 1000;
    CHECK(message(small).find("max_pixels") != std::string::npos);
    std::filesystem::remove(path);
}

TEST_CASE("io: OBJ loading, materials, and errors that name the file") {
    const std::string dir = temp_path("obj");
    std::filesystem::create_directories(dir);
    {
        std::ofstream(dir + "/quad.mtl") << "newmtl lamp\nKd 0 0 0\nKe 5 4 3\nnewmtl wall\nKd 0.5 0.6 0.7\n";
        std::ofstream(dir + "/quad.obj") << "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                            "usemtl wall\nf 1 2 3 4\nusemtl lamp\nf 1 3 4\n";
        std::ofstream(dir + "/bad.obj") << "v 0 0 0\nv 1 0 0\nf 1 2 7\n";
    }
    const ObjMesh m = load_obj(dir + "/quad.obj");
    REQUIRE(m.triangles.size() == 3);  // the quad fan-triangulated, plus one triangle
    CHECK(m.materials[m.material[0]].kd == Rgb<float>(0.5f, 0.6f, 0.7f));
    CHECK(m.materials[m.material[2]].ke == Rgb<float>(5.0f, 4.0f, 3.0f));
    try {
        load_obj(dir + "/missing.obj");
        FAIL("no error for a missing file");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find("missing.obj") != std::string::npos);
    }
    try {
        load_obj(dir + "/bad.obj");
        FAIL("no error for a face with an out-of-range vertex");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find("bad.obj") != std::string::npos);
    }
    std::filesystem::remove_all(dir);
}

namespace {

/// Loads `obj` (and `mtl` as scene.mtl beside it) from a scratch folder; returns the error
/// message, or "" when it loads.
std::string obj_error(const std::string& obj, const std::string& mtl = "", ObjMesh* out = nullptr) {
    const std::string dir = temp_path("objv");
    std::filesystem::create_directories(dir);
    std::ofstream(dir + "/scene.obj") << obj;
    if (!mtl.empty()) std::ofstream(dir + "/scene.mtl") << mtl;
    std::string msg;
    try {
        ObjMesh m = load_obj(dir + "/scene.obj");
        if (out) *out = std::move(m);
    } catch (const Error& e) {
        msg = e.what();
    }
    std::filesystem::remove_all(dir);
    return msg;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

/// The numbers of the JSON array that follows `key` in `text` (nested brackets flattened).
std::vector<double> json_array_numbers(const std::string& text, const std::string& key) {
    std::size_t p = text.find("\"" + key + "\": [");
    REQUIRE(p != std::string::npos);
    p = text.find('[', p);
    std::vector<double> out;
    int depth = 0;
    for (std::size_t i = p; i < text.size(); ++i) {
        const char c = text[i];
        if (c == '[') ++depth;
        else if (c == ']' && --depth == 0) break;
        else if (c == '-' || (c >= '0' && c <= '9')) {
            char* end = nullptr;
            out.push_back(std::strtod(text.c_str() + i, &end));
            i = std::size_t(end - text.c_str()) - 1;
        }
    }
    return out;
}

}  // namespace

TEST_CASE("io: OBJ validation: non-finite vertices are errors naming file, line and value") {
    const std::string quad = "f 1 2 3\n";
    for (const char* bad : {"nan", "inf", "-inf", "1e39", "abc"}) {
        CAPTURE(bad);
        const std::string e = obj_error(std::string("v 0 0 0\nv ") + bad + " 1 0\nv 0 1 0\n" + quad);
        CHECK(contains(e, "scene.obj:2"));
        CHECK(contains(e, bad));
    }
    CHECK(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\n" + quad).empty());
}

TEST_CASE("io: OBJ validation: Kd/Ks negative or non-finite, Ke negative or non-finite are errors; Kd > 1 clamps with a warning") {
    const std::string obj = "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";
    for (const char* line : {"Kd nan 0.5 0.5", "Kd -0.5 0.5 0.5", "Ks 0.1 inf 0.1", "Ke inf 1 1", "Ke -5 -5 -5", "Ke nan 0 0"}) {
        CAPTURE(line);
        const std::string e = obj_error(obj, std::string("newmtl m\n") + line + "\n");
        CHECK(contains(e, "scene.mtl:2"));
        CHECK(contains(e, "material 'm'"));
        CHECK(contains(e, std::string(line).substr(0, 2)));
    }
    ObjMesh m;
    CHECK(obj_error(obj, "newmtl m\nKd 1.5 0.5 0.25\nKe 2 3 4\n", &m).empty());
    REQUIRE(m.triangles.size() == 1);
    CHECK(m.materials[m.material[0]].kd == Rgb<float>(1.0f, 0.5f, 0.25f));
    CHECK(m.materials[m.material[0]].ke == Rgb<float>(2.0f, 3.0f, 4.0f));
    REQUIRE(m.warnings.size() == 1);
    CHECK(contains(m.warnings[0], "Kd"));
    CHECK(contains(m.warnings[0], "clamped"));
}

TEST_CASE("io: OBJ validation: Ns and Ni non-finite or negative, Ni zero, are errors naming file, line and value") {
    const std::string obj = "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";
    for (const char* line : {"Ni nan", "Ns -5", "Ns inf", "Ni -1.5", "Ni 0", "Ns"}) {
        CAPTURE(line);
        const std::string e = obj_error(obj, std::string("newmtl m\nKd 0.5 0.5 0.5\n") + line + "\n");
        CHECK(contains(e, "scene.mtl:3"));
        CHECK(contains(e, "material 'm' " + std::string(line).substr(0, 2)));
    }
    ObjMesh m;
    CHECK(obj_error(obj, "newmtl m\nNs 0\nNi 1.5\n", &m).empty());
    CHECK(m.materials[m.material[0]].ni == 1.5f);
}

TEST_CASE("io: OBJ validation: faces of zero area are kept with one warning naming the first line") {
    ObjMesh m;
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 2 4 1\n";
    CHECK(obj_error(obj, "", &m).empty());
    CHECK(m.triangles.size() == 3);
    REQUIRE(m.warnings.size() == 1);
    CHECK(contains(m.warnings[0], "scene.obj:6: 2 triangle(s) of zero area"));
    // An emissive face of zero area is an error (it would divide by its area when sampled).
    const std::string e = obj_error("mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nusemtl l\nf 1 2 3\n", "newmtl l\nKe 1 1 1\n");
    CHECK(contains(e, "scene.obj:6: emissive face"));
}

TEST_CASE("io: OBJ validation: a missing MTL is a warning, the faces get the default material") {
    ObjMesh m;
    CHECK(obj_error("mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n", "", &m).empty());
    REQUIRE(m.triangles.size() == 1);
    CHECK(m.materials[m.material[0]].name == "default");
    REQUIRE(!m.warnings.empty());
    CHECK(contains(m.warnings[0], "nowhere.mtl"));
    ObjMesh clean;
    CHECK(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "", &clean).empty());
    CHECK(clean.warnings.empty());
}

TEST_CASE("io: OBJ validation: a 300-gon is fan-triangulated, and the faces after it keep their vertices") {
    // tinyobjloader stores a face's vertex count in an unsigned char: 300 would read as 44.
    std::ostringstream obj;
    const int n = 300;
    const double pi = 3.14159265358979323846;
    for (int k = 0; k < n; ++k) obj << "v " << std::cos(2 * pi * k / n) << " " << std::sin(2 * pi * k / n) << " 0\n";
    obj << "v 0 0 5\nv 1 0 5\nv 0 1 5\nf";
    for (int k = 1; k <= n; ++k) obj << " " << k;
    obj << "\nf " << n + 1 << " " << n + 2 << " " << n + 3 << "\n";
    ObjMesh m;
    CHECK(obj_error(obj.str(), "", &m).empty());
    REQUIRE(m.triangles.size() == std::size_t(n - 2 + 1));
    double area = 0;
    for (std::size_t i = 0; i + 1 < m.triangles.size(); ++i) {
        const auto& t = m.triangles[i];
        area += 0.5 * double(glm::length(glm::cross(t[1] - t[0], t[2] - t[0])));
        CHECK(m.line[i] == std::uint32_t(n + 4));
    }
    CHECK(area == doctest::Approx(0.5 * n * std::sin(2 * pi / n)).epsilon(1e-5));  // the regular 300-gon's area
    const auto& last = m.triangles.back();
    CHECK(last[0] == Vec3f(0, 0, 5));
    CHECK(last[1] == Vec3f(1, 0, 5));
    CHECK(last[2] == Vec3f(0, 1, 5));
    CHECK(m.line.back() == std::uint32_t(n + 5));
}

TEST_CASE("io: OBJ validation: out-of-range face indices name the line and the index as written") {
    const std::string e = obj_error("v 0 0 0\nv 1 0 0\nf 1 2 -9\n");
    CHECK(contains(e, "scene.obj:3"));
    CHECK(contains(e, "-9"));
    CHECK(contains(e, "2 vertices"));
    const std::string e2 = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 7\n");
    CHECK(contains(e2, "scene.obj:5"));
    CHECK(contains(e2, "vertex 7"));
    CHECK(contains(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n"), "scene.obj:4"));
    CHECK(contains(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 0 2\n"), "index 0"));
    CHECK(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n").empty());
    CHECK(contains(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -99999999999999999999999\n"), "out of range"));
    CHECK(contains(obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3000000000\n"), "out of range"));
}

TEST_CASE("io: OBJ validation: lines end at \\n, \\r\\n or a lone \\r, as tinyobjloader splits them") {
    // A lone \r ends a line for tinyobjloader, so the checks must split there too: otherwise
    // "usemtl m\rf 1 2 9" hides an out-of-range face from the index check (a fuzz finding).
    CHECK(contains(obj_error("v 0 0 0\rv 1 0 0\rv 0 1 0\rusemtl m\rf 1 2 9\r"), "scene.obj:5"));
    CHECK(contains(obj_error("v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\n\r\nf 1 2 7\r\n"), "scene.obj:5"));
    const std::string mtl_e = obj_error("mtllib scene.mtl\rv 0 0 0\rv 1 0 0\rv 0 1 0\rusemtl m\rf 1 2 3\r",
                                        "newmtl m\rKd -1 0 0\r");
    CHECK(contains(mtl_e, "scene.mtl:2"));
    ObjMesh m;
    CHECK(obj_error("v 0 0 0\rv 1 0 0\r\nv 0 1 0\nf 1 2 3", "", &m).empty());
    REQUIRE(m.triangles.size() == 1);
    CHECK(m.triangles[0][1] == Vec3f(1, 0, 0));
    CHECK(m.line[0] == 4u);
}

TEST_CASE("io: OBJ validation: a zero-area emissive face names the file, line and material") {
    const std::string e = obj_error("mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nusemtl lamp\nf 1 2 4\nf 1 2 3\n",
                                    "newmtl lamp\nKd 0 0 0\nKe 5 5 5\n");
    CHECK(contains(e, "scene.obj:8"));
    CHECK(contains(e, "lamp"));
    CHECK(contains(e, "zero area"));
}


TEST_CASE("io: scene JSON export writes every triangle, material and the camera exactly") {
    Scene<float> s = builtin_scene<float>("cornell-glossy");
    // One triangle whose coordinates need all 9 digits (the scene's own are short decimals).
    const std::array<Vec3f, 3> odd{Vec3f(1.0f / 3.0f, 2.0f / 7.0f, -5.0f / 11.0f), Vec3f(std::nextafter(1.0f, 2.0f), 0.1f, 1e-8f),
                                   Vec3f(-1.0f / 9.0f, 3.0f / 13.0f, 7.0f / 17.0f)};
    s.add_polygon(odd, 0);
    s.point_lights.push_back(PointLight<float>::spot(Vec3f(0, 1.9f, 0), Vec3f(0, -1, 0), Rgb<float>(3, 2, 1), 0.5f, 0.25f));
    std::ostringstream out;
    write_scene_json(out, s, SceneJsonView{64, 32, 17});
    const std::string text = out.str();
    const std::vector<double> tris = json_array_numbers(text, "triangles");
    REQUIRE(tris.size() == 9 * s.triangles.size());
    int wrong = 0;  // 9 significant digits: every float comes back exactly
    for (std::size_t i = 0; i < s.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) wrong += float(tris[9 * i + 3 * std::size_t(k) + std::size_t(c)]) != s.triangles[i][k][c];
    CHECK(wrong == 0);
    const std::vector<double> mat_of = json_array_numbers(text, "material_of");
    REQUIRE(mat_of.size() == s.material_of.size());
    for (std::size_t i = 0; i < mat_of.size(); ++i) wrong += std::uint32_t(mat_of[i]) != s.material_of[i];
    CHECK(wrong == 0);
    CHECK(text.find("\"kind\": \"glossy\"") != std::string::npos);
    CHECK(text.find("\"exponent\": 40") != std::string::npos);
    CHECK(text.find("\"emission\": [17, 12, 4]") != std::string::npos);
    CHECK(text.find("\"fov_y\": 0.680000007") != std::string::npos);
    CHECK(text.find("\"width\": 64,\n  \"height\": 32,\n  \"aspect\": 2,\n  \"max_depth\": 17") != std::string::npos);
    CHECK(json_array_numbers(text, "area_lights").size() == 4 * 3 + 3 + 3 + 1);  // quad, emission, normal, area
    CHECK(text.find("\"kind\": \"spot\", \"position\": [0, 1.89999998, 0], \"intensity\": [3, 2, 1]") != std::string::npos);
    // position, intensity, axis, cos_outer, cos_inner
    CHECK(json_array_numbers(text, "point_lights").size() == 3 + 3 + 3 + 1 + 1);
    CHECK_THROWS_AS(write_scene_json(out, builtin_scene<float>("envmap"), SceneJsonView{}), Error);
    s.triangles[3][1].x = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_AS(write_scene_json(out, s, SceneJsonView{}), Error);
    CHECK_THROWS_AS(write_scene_json(out, builtin_scene<float>("cornell"), SceneJsonView{0, 8, 64}), Error);
}

TEST_CASE("insert_mesh: a generated mesh scaled to its footprint, standing on the floor at its base") {
    Scene<float> box;  // a 4 x 2 x 3 box, far from the origin: 12 triangles
    box.add_material(Material<float>::lambertian(Rgb<float>(0.5f)));
    detail::add_box(box, Vec3f(-3, 5, -1), Vec3f(1, 7, 2), 0.0f, 0);
    Scene<float> s = builtin_scene<float>("cornell");
    const std::size_t before = s.triangles.size(), lights = s.area_lights.size();
    const MeshPlacement<float> p{Vec3f(0.5f, 0.0f, -0.2f), 0.8f};  // scale 0.8 / 4 = 0.2
    const std::uint32_t m = insert_mesh<float>(s, box.triangles, Material<float>::lambertian(Rgb<float>(0.3f)), p);
    REQUIRE(s.triangles.size() == before + 12);
    CHECK(m == s.materials.size() - 1);
    CHECK(s.area_lights.size() == lights);
    AABB<float> placed;
    for (std::size_t i = before; i < s.triangles.size(); ++i) {
        CHECK(s.material_of[i] == m);
        CHECK(s.light_of[i] == -1);
        // Uniform positive scale and a translation keep each face's normal (its winding).
        CHECK(glm::dot(s.normal(i), box.normal(i - before)) == doctest::Approx(1.0f).epsilon(1e-5));
        for (const auto& v : s.triangles[i]) placed.extend(v);
    }
    const float e = 1e-5f;
    CHECK(placed.lo.x == doctest::Approx(0.1f).epsilon(e));
    CHECK(placed.hi.x == doctest::Approx(0.9f).epsilon(e));
    CHECK(placed.lo.y == doctest::Approx(0.0f).epsilon(e));
    CHECK(placed.hi.y == doctest::Approx(0.4f).epsilon(e));
    CHECK(placed.lo.z == doctest::Approx(-0.5f).epsilon(e));
    CHECK(placed.hi.z == doctest::Approx(0.1f).epsilon(e));
    // The Cornell placement is clear of both boxes and the walls (what glint-render uses).
    const MeshPlacement<float> c = cornell_mesh_placement<float>();
    CHECK(c.base.x - c.size / 2 > -0.99f);
    CHECK(c.base.z + c.size / 2 < 0.99f);
    CHECK(c.base.x + c.size / 2 < -0.05f);  // the short box starts at x = -0.05
    CHECK(c.base.z - c.size / 2 > 0.09f);   // the tall box ends at z = 0.09
    CHECK_THROWS_AS(insert_mesh<float>(s, {}, Material<float>::lambertian(Rgb<float>(0.3f)), p), Error);
    CHECK_THROWS_AS(insert_mesh<float>(s, box.triangles, Material<float>::lambertian(Rgb<float>(0.3f)),
                                       MeshPlacement<float>{Vec3f(0.0f), 0.0f}),
                    Error);
}

TEST_CASE("reduced continuation: s_new = s d / (1 - (1 - d) s), unchanged at d = 1") {
    Roulette<double, 3> est = Roulette<double, 3>::classic(Rgb<double>(1.0 / 3.0));
    est.estimate = Rgb<double>(0.2);
    const Rgb<double> F(1.0), a(0.6);
    const Roulette<double, 3> same = est;
    Roulette<double, 3> shorter = est;
    shorter.goodness = 0.25;
    CHECK(same.continuation(F, a, 0) == doctest::Approx(0.6));
    CHECK(shorter.continuation(F, a, 0) == doctest::Approx(0.6 * 0.25 / (1.0 - 0.75 * 0.6)));
    // What s_new is for (Szécsi 2009, §2.3): the variance termination adds, (1/s - 1) E[..^2],
    // is the same with the estimate at goodness d and s_new as without it at s_old.
    const double s_new = shorter.continuation(F, a, 0), d = 0.25;
    CHECK((1.0 / s_new - 1.0) * d == doctest::Approx(1.0 / 0.6 - 1.0));
    // The speedup Szécsi 2009, §2.3 predicts, measured: walks continued with probability s (walk
    // length = number of continuations + 1, geometric) at s_old and s_new, fixed seed; the
    // ratio of mean lengths must be 1 / (1 - (1 - d) s_old) within 4 standard errors (delta
    // method on the two means, variance s / (1 - s)^2 each).
    Pcg32 rng(2024);
    const auto mean_length = [&](double s, int n) {
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            int len = 1;
            while (rng.uniform<double>() < s) ++len;
            sum += len;
        }
        return sum / n;
    };
    const int n = 200000;
    const double l_old = mean_length(0.6, n), l_new = mean_length(s_new, n);
    const double ratio = l_old / l_new, expected = 1.0 / (1.0 - (1.0 - d) * 0.6);
    const double var_old = 0.6 / ((1 - 0.6) * (1 - 0.6)), var_new = s_new / ((1 - s_new) * (1 - s_new));
    const double se = ratio * std::sqrt(var_old / (n * l_old * l_old) + var_new / (n * l_new * l_new));
    INFO("walk length ratio ", ratio, " expected ", expected, " se ", se);
    CHECK(std::abs(ratio - expected) <= 4 * se);
    CHECK(shorter.terminated(a) == est.terminated(a));
}

TEST_CASE("scale and translation: the Cornell box renders the same image wherever float resolves it") {
    // Ray origins leave surfaces by the rounding-error bound of the surface point, which scales
    // with the coordinates (no absolute epsilon): the box moved up to 10^5 away or scaled by
    // 10^-4 ... 10^4 gives the untransformed image's mean in every band and in each image half
    // (left/right: the red and the green wall), within 4 standard errors of the difference.
    const Scene<float> base = builtin_scene<float>("cornell");
    NamedRender<float> o;
    o.image.width = o.image.height = 24;
    o.image.spp = 64;
    o.roulette = "throughput";
    const auto halves = [](const RenderResult& r, std::array<double, 6>& m, std::array<double, 6>& var) {
        m.fill(0);
        var.fill(0);
        for (int y = 0; y < r.image.height; ++y)
            for (int x = 0; x < r.image.width; ++x)
                for (std::size_t c = 0; c < 3; ++c) {
                    const std::size_t k = (x < r.image.width / 2 ? 0 : 3) + c;
                    m[k] += r.image.at(x, y)[c];
                    var[k] += r.variance.at(x, y)[c];
                }
    };
    std::array<double, 6> m0, v0;
    halves(render_scene(base, o), m0, v0);
    const std::vector<std::pair<double, double>> moves = {{1e3, 1}, {1e4, 1}, {3e4, 1}, {1e5, 1}, {0, 1e-4},
                                                          {0, 1e-2}, {0, 1e2}, {0, 1e4}, {1, 1e-4}};
    for (const auto& move_by : moves) {
        const double translation = move_by.first, scale = move_by.second;  // not a structured binding: clang 14 cannot capture one
        Scene<float> s = base;
        const auto move = [&](Vec3<float>& p) { p = Vec3<float>(Vec3<double>(p) * scale + Vec3<double>(translation)); };
        for (auto& t : s.triangles)
            for (auto& v : t) move(v);
        for (auto& l : s.area_lights) {
            for (auto& v : l.vertices) move(v);
            l.area *= float(scale * scale);
        }
        move(s.camera.eye);
        move(s.camera.target);
        ++o.seed;
        std::array<double, 6> m, v;
        halves(render_scene(s, o), m, v);
        for (std::size_t k = 0; k < 6; ++k) {
            CAPTURE(translation);
            CAPTURE(scale);
            CAPTURE(k);
            CAPTURE(m[k]);
            CAPTURE(m0[k]);
            CHECK(std::abs(m[k] - m0[k]) < 4.0 * std::sqrt(v[k] + v0[k]));
        }
    }
}

TEST_CASE("depth cap: far out of reach by default, and walks it cuts are counted") {
    // A grey furnace of albedo 0.99 and emission 0.01 has radiance 1 everywhere; walks are
    // ~100 vertices long. With the default cap (1024) the image is 1 within 4 standard errors;
    // a cap of 64 cuts most walks (biased: about 1 - 0.99^64 = 47% of the light reaches the
    // camera), and the result says how many it cut.
    Scene<float> s = builtin_scene<float>("furnace");
    for (auto& m : s.materials) {
        m.kd = Rgb<float>(0.99f);
        m.ks = Rgb<float>(0.0f);
        m.emission = Rgb<float>(0.01f);
    }
    NamedRender<float> o;
    o.image.width = o.image.height = 12;
    o.image.spp = 32;
    o.direct = "brdf";
    o.roulette = "throughput";
    const RenderResult r = render_scene(s, o);
    Rgb<double> mean, se;
    image_mean(r, mean, se);
    const double paths = double(r.paths);
    CHECK(r.paths == std::uint64_t(12 * 12 * 32));
    CHECK(double(r.capped_walks) < 1e-3 * paths);
    CHECK(std::abs(mean[0] - 1.0) < 4.0 * se[0]);
    o.tracer.max_depth = 64;
    const RenderResult capped = render_scene(s, o);
    image_mean(capped, mean, se);
    CHECK(double(capped.capped_walks) > 0.3 * paths);
    CHECK(mean[0] < 0.7);
}

namespace {

/// A square [-1, 1]^2 at z = 0 facing the camera on +z, Lambertian `kd` and emitting 1: alone
/// in the dark, every camera ray that hits it carries exactly radiance 1 (it cannot light itself).
Scene<float> lone_emitting_square(const Rgb<float>& kd) {
    Scene<float> s;
    s.name = "square";
    const std::uint32_t m = s.add_material(Material<float>::lambertian(kd, Rgb<float>(1.0f)));
    s.add_quad(Vec3f(-1, -1, 0), Vec3f(1, -1, 0), Vec3f(1, 1, 0), Vec3f(-1, 1, 0), m);
    s.camera = Camera<float>{Vec3f(0.1f, 0.2f, 4.0f), Vec3f(0.1f, 0.2f, 0.0f), Vec3f(0, 1, 0), 0.7f};
    return s;
}

}  // namespace

TEST_CASE("first-hit layers: the beauty pass's pixel filter, unit normals inside a plane, depth the ray distance") {
    const Rgb<float> kd(0.6f, 0.4f, 0.2f);
    const Scene<float> s = lone_emitting_square(kd);
    const DefaultAccel accel(s.triangles);
    NamedRender<float> o;
    o.image.width = 24;
    o.image.height = 20;
    o.image.spp = 8;
    o.image.threads = 2;
    o.seed = 3;
    // Jittered samples: each pixel's albedo is kd times the share of its rays that hit, the
    // share the beauty pass (radiance 1 on the square, 0 elsewhere) sees, to float rounding.
    const RenderResult beauty = render_named(s, any_accel_view(accel), o);
    const FirstHitImages f = render_first_hit_named(s, any_accel_view(accel), o);
    int partial = 0, full = 0, empty = 0, bad = 0;
    for (std::size_t i = 0; i < beauty.image.pixels.size(); ++i) {
        const float cover = beauty.image.pixels[i][0];
        for (std::size_t c = 0; c < 3; ++c) bad += std::abs(f.albedo.pixels[i][c] - kd[c] * cover) > 1e-6f;
        const Rgb<float> n = f.normal.pixels[i];
        bad += std::abs(n[2] - cover) > 1e-6f || n[0] != 0.0f || n[1] != 0.0f;  // (0, 0, 1) times the share
        if (cover == 1.0f) ++full;
        else if (cover == 0.0f) {
            ++empty;
            bad += !std::isinf(f.depth.pixels[i]);
        } else ++partial;
        if (cover > 0.0f) bad += !(f.depth.pixels[i] >= 4.0f && f.depth.pixels[i] < 4.5f);
    }
    CHECK(bad == 0);
    CHECK(partial > 10);  // pixels straddling the square's edges were compared too
    CHECK(full > 100);
    CHECK(empty > 10);
    // Pixel centres: the depth is the distance to the plane along the centre ray.
    o.image.pixel_jitter = false;
    const FirstHitImages c = render_first_hit_named(s, any_accel_view(accel), o);
    int hits = 0, wrong = 0;
    for (int y = 0; y < o.image.height; ++y)
        for (int x = 0; x < o.image.width; ++x) {
            const Ray<float> r = s.camera.ray((float(x) + 0.5f) / 24.0f, (float(y) + 0.5f) / 20.0f, 24.0f / 20.0f);
            const Vec3f p = r.origin + r.direction * (4.0f / -r.direction.z);
            const bool in = std::abs(p.x) < 1 && std::abs(p.y) < 1;
            if (!in) continue;
            ++hits;
            wrong += std::abs(c.depth.at(x, y) - glm::length(p - r.origin)) > 1e-5f * 4 ||
                     std::abs(glm::length(Vec3f(c.normal.at(x, y)[0], c.normal.at(x, y)[1], c.normal.at(x, y)[2])) - 1) > 1e-6f;
        }
    CHECK(hits > 100);
    CHECK(wrong == 0);
}

TEST_CASE("first-hit layers: a diffuse Cornell wall's albedo is its reflectance") {
    // Centre rays, traced again here through the same tree: the box's edge with the floor lies
    // on the image's diagonal, where another tree or triangle test may pick the other side.
    const Scene<float> s = builtin_scene<float>("cornell");
    const DefaultAccel accel(s.triangles);
    NamedRender<float> o;
    o.image.width = o.image.height = 32;
    o.image.spp = 2;
    o.image.pixel_jitter = false;
    const FirstHitImages f = render_first_hit_named(s, any_accel_view(accel), o);
    std::map<std::uint32_t, int> seen;  // material -> pixels showing it
    int differ = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            StoreHit<float> hit;
            const Ray<float> r = s.camera.ray((float(x) + 0.5f) / 32.0f, (float(y) + 0.5f) / 32.0f, 1.0f);
            if (!accel.closest_hit(r, hit)) continue;
            const std::uint32_t m = s.material_of[hit.id];
            const Material<float>& mat = s.materials[m];
            if (mat.kind != MaterialKind::lambertian) continue;
            differ += f.albedo.at(x, y) != mat.kd;  // exactly: both samples of a centre see the same
            ++seen[m];
        }
    CHECK(differ == 0);
    int coloured = 0;  // the red and the green wall, each seen over many pixels
    for (const auto& [m, pixels] : seen) coloured += s.materials[m].kd.max() > 3 * s.materials[m].kd.min() && pixels > 50;
    CHECK(coloured == 2);
}

TEST_CASE("shading normals: corner normals interpolate, turn to the shaded side, and are validated") {
    Scene<float> s;
    s.add_material(Material<float>::lambertian(Rgb<float>(0.5f)));
    const std::array<Vec3f, 3> tri{Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)};
    s.add_polygon(tri, 0);
    const Vec3f ng(0, 0, 1);
    CHECK(s.shading_normal(0, 0.2f, 0.3f, ng) == ng);  // no corner normals: the geometric one
    const Vec3f a = glm::normalize(Vec3f(0.3f, 0, 1)), b = glm::normalize(Vec3f(0, 0.4f, 1)), c = glm::normalize(Vec3f(-0.2f, -0.1f, 1));
    s.corner_normals = {{a, b, c}};
    s.validate();
    CHECK(glm::length(s.shading_normal(0, 0, 0, ng) - a) < 1e-6f);  // the corners, in vertex order
    CHECK(glm::length(s.shading_normal(0, 1, 0, ng) - b) < 1e-6f);
    CHECK(glm::length(s.shading_normal(0, 0, 1, ng) - c) < 1e-6f);
    const Vec3f mid = glm::normalize(0.5f * a + 0.2f * b + 0.3f * c);
    CHECK(glm::length(s.shading_normal(0, 0.2f, 0.3f, ng) - mid) < 1e-6f);
    CHECK(glm::length(s.shading_normal(0, 0.2f, 0.3f, -ng) + mid) < 1e-6f);  // the back side: turned over
    s.corner_normals = {{a, b, -a}};  // cancel at the midpoint of the first and last corner
    CHECK(s.shading_normal(0, 0, 0.5f, ng) == ng);
    s.corner_normals = {{a, b, Vec3f(0, 0, 2)}};
    CHECK_THROWS_WITH_AS(s.validate(), doctest::Contains("triangle 0 has a corner normal of length 2"), Error);
    s.corner_normals = {{a, b, c}, {a, b, c}};
    CHECK_THROWS_WITH_AS(s.validate(), doctest::Contains("2 triangles' corner normals for 1 triangles"), Error);
}

TEST_CASE("shading normals: a point light's direct light uses the interpolated normal's cosine, exactly") {
    // One triangle in z = 0 facing +z whose corners' normals lean different ways; camera rays
    // straight down at points of known barycentrics; an isotropic point light above. With one
    // vertex (max_depth 1) the radiance is kd / pi * I * cos(n_s, wi) / r^2: no randomness.
    Scene<float> s;
    s.add_material(Material<float>::lambertian(Rgb<float>(0.5f)));
    const std::array<Vec3f, 3> tri{Vec3f(-1, -1, 0), Vec3f(2, -1, 0), Vec3f(-1, 2, 0)};
    s.add_polygon(tri, 0);
    const std::array<Vec3f, 3> corner{glm::normalize(Vec3f(0.6f, 0, 1)), glm::normalize(Vec3f(0, -0.7f, 1)),
                                      glm::normalize(Vec3f(-0.5f, 0.5f, 1))};
    s.corner_normals = {corner};
    s.point_lights.push_back(PointLight<float>{Vec3f(0.4f, 0.3f, 1.5f), Rgb<float>(4.0f)});
    const BruteForce<Ivm<float>> accel(s.triangles);
    PathTracerSettings<float> settings{.roulette = Roulette<float, 3>::classic()};
    settings.max_depth = 1;
    PathTracer<BruteForce<Ivm<float>>, RandomSampler<float>, MisDirect<float>> pt(s, accel, settings);
    RandomSampler<float> sampler(3);
    for (const std::array<float, 2>& uv : {std::array{0.2f, 0.3f}, std::array{0.6f, 0.1f}, std::array{0.05f, 0.8f}}) {
        const float u = uv[0], v = uv[1];  // not a structured binding: clang 14's lambdas (CAPTURE) cannot take one
        const Vec3f x = tri[0] * (1 - u - v) + tri[1] * u + tri[2] * v;
        const Vec3f ns = glm::normalize(corner[0] * (1 - u - v) + corner[1] * u + corner[2] * v);
        const Vec3f d = s.point_lights[0].position - x;
        const float cos_s = glm::dot(ns, glm::normalize(d)), cos_g = glm::normalize(d).z;
        const float expected = 0.5f / pi<float> * 4.0f * cos_s / glm::dot(d, d);
        sampler.start_pixel_sample(0, 0, 0);
        const float L = pt.radiance(Ray<float>{x + Vec3f(0, 0, 1), Vec3f(0, 0, -1)}, sampler).L[0];
        CAPTURE(u);
        CHECK(L == doctest::Approx(expected).epsilon(1e-4));
        CHECK(std::abs(cos_s - cos_g) > 0.05f * cos_g);  // the geometric normal would give another value
    }
}

TEST_CASE("io: OBJ vertex normals become per-corner shading normals; bad ones name the line") {
    const std::string dir = temp_path("obj_vn");
    std::filesystem::create_directories(dir);
    {
        // A quad with v//vn (fan-triangulated: corners 1 2 3 and 1 3 4), a triangle with
        // v/vt/vn, and one without normals (its geometric normal at every corner).
        std::ofstream(dir + "/vn.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\n"
                                          "vn 0 0 2\nvn 0 1 1\nvn 1 0 1\nvn 0 0 -3\n"
                                          "f 1//1 2//2 3//3 4//4\nf 1/1/2 2/1/3 4/1/1\nf 1 4 2\n";
        std::ofstream(dir + "/none.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        std::ofstream(dir + "/zero.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn 0 0 1\nf 1//2 2//1 3//2\n";
        std::ofstream(dir + "/missing.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n\nf 1//1 2//1 3//5\n";
    }
    const ObjMesh m = load_obj(dir + "/vn.obj");
    REQUIRE(m.triangles.size() == 4);
    REQUIRE(m.normals.size() == 4);
    const Vec3f z(0, 0, 1), y = glm::normalize(Vec3f(0, 1, 1)), x = glm::normalize(Vec3f(1, 0, 1));
    auto near = [](const Vec3f& p, const Vec3f& q) { return glm::length(p - q) < 1e-6f; };
    CHECK((near(m.normals[0][0], z) && near(m.normals[0][1], y) && near(m.normals[0][2], x)));
    CHECK((near(m.normals[1][0], z) && near(m.normals[1][1], x) && near(m.normals[1][2], -z)));
    CHECK((near(m.normals[2][0], y) && near(m.normals[2][1], x) && near(m.normals[2][2], z)));
    CHECK((near(m.normals[3][0], -z) && near(m.normals[3][1], -z) && near(m.normals[3][2], -z)));  // f 1 4 2 winds to -z
    const Scene<float> s = obj_scene(m, "vn");
    CHECK(s.corner_normals == m.normals);
    s.validate();
    CHECK(load_obj(dir + "/none.obj").normals.empty());
    CHECK(obj_scene(load_obj(dir + "/none.obj"), "none").corner_normals.empty());
    CHECK_THROWS_WITH_AS(load_obj(dir + "/zero.obj"), doctest::Contains("zero.obj:6: the face's normal vn 1 has length 0"), Error);
    CHECK_THROWS_WITH_AS(load_obj(dir + "/missing.obj"), doctest::Contains("missing.obj:6: the face names normal 5 but there are 1 vn lines"), Error);
}

namespace {

/// The cube [-1, 1]^3 as six quads facing out (two triangles each).
Scene<float> cube_scene() {
    Scene<float> s;
    const auto m = s.add_material(Material<float>::lambertian(Rgb<float>(0.5f)));
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.0f, 1.0f}) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            std::array<Vec3f, 4> q{};
            const float uv[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
            for (int k = 0; k < 4; ++k) {
                q[std::size_t(k)][axis] = side;
                q[std::size_t(k)][u] = uv[k][0] * side;  // counter-clockwise seen from outside
                q[std::size_t(k)][v] = uv[k][1];
            }
            s.add_polygon(q, m);
        }
    return s;
}

/// Checks the rays a render casts from the plane z = 0 (camera rays start at z = 1 or above):
/// each must start on the side its direction leaves to; counts them and those going down.
struct PlaneSideRecorder {
    using scalar_type = float;
    const BruteForce<Ivm<float>>& inner;
    mutable std::uint64_t from_floor = 0, wrong_side = 0, below = 0;
    void check(const Ray<float>& r) const {
        if (std::abs(r.origin.z) >= 0.5f) return;  // a camera ray
        ++from_floor;
        if (!(r.origin.z * r.direction.z > 0.0f)) ++wrong_side;
        below += r.direction.z < 0.0f;
    }
    bool closest_hit(const Ray<float>& r, StoreHit<float>& h) const {
        check(r);
        return inner.closest_hit(r, h);
    }
    bool any_hit(const Ray<float>& r) const {
        check(r);
        return inner.any_hit(r);
    }
};

}  // namespace

TEST_CASE("smooth_corner_normals: angle-weighted within the crease angle; a cube's edges stay sharp below 90 degrees") {
    Scene<float> s = cube_scene();
    smooth_corner_normals(s, 60.0f);
    s.validate();
    for (std::size_t t = 0; t < s.triangles.size(); ++t)
        for (const Vec3f& c : s.corner_normals[t]) CHECK(glm::length(c - s.normal(t)) < 1e-6f);
    smooth_corner_normals(s, 100.0f);  // every corner: the three faces' mean, whatever their triangulation
    for (std::size_t t = 0; t < s.triangles.size(); ++t)
        for (std::size_t k = 0; k < 3; ++k) {
            CAPTURE(t);
            CHECK(glm::length(s.corner_normals[t][k] - s.triangles[t][k] / std::sqrt(3.0f)) < 1e-5f);
        }
    CHECK_THROWS_WITH_AS(smooth_corner_normals(s, 200.0f), doctest::Contains("crease angle 200"), Error);
}

TEST_CASE("shading normals never start a ray on the wrong side of the geometric surface") {
    // A floor z = 0 whose corner normals all lean 70 degrees towards +x: the shading
    // hemisphere reaches far below the floor. Every ray the path tracer casts from the floor
    // (BRDF samples, shadow rays to the point light above and to the lamp) must start on the
    // side of the geometric surface it leaves to; some do leave downwards (the lean's cost).
    Scene<float> s;
    const auto m = s.add_material(Material<float>::lambertian(Rgb<float>(0.7f)));
    s.add_quad({-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}, m);
    const auto lamp = s.add_material(Material<float>::lambertian(Rgb<float>(0), Rgb<float>(3)));
    s.add_quad({-0.5f, -0.5f, 2}, {-0.5f, 0.5f, 2}, {0.5f, 0.5f, 2}, {0.5f, -0.5f, 2}, lamp);
    s.fill_corner_normals();
    const Vec3f lean(std::sin(1.22f), 0, std::cos(1.22f));
    for (std::size_t t = 0; t < 2; ++t) s.corner_normals[t] = {lean, lean, lean};
    s.point_lights.push_back(PointLight<float>{Vec3f(0.3f, 0.2f, 1.0f), Rgb<float>(2.0f)});
    s.camera = Camera<float>{{0, -3, 3}, {0, 0, 0}, {0, 0, 1}, 0.8f};
    const BruteForce<Ivm<float>> bf(s.triangles);
    const PlaneSideRecorder rec{bf};
    PathTracerSettings<float> settings{.roulette = Roulette<float, 3>::classic()};
    settings.max_depth = 4;
    PathTracer<PlaneSideRecorder, RandomSampler<float>, MisDirect<float>> pt(s, rec, settings);
    RandomSampler<float> sampler(5);
    RenderSettings image;
    image.width = image.height = 16;
    const PixelCamera<float> camera(s.camera, image);
    for (int i = 0; i < 4096; ++i) {
        const Rgb<float> L = pt.radiance(camera.ray(i % 16, i / 16 % 16, std::uint64_t(i), sampler), sampler).L;
        REQUIRE(L.is_finite());
    }
    CHECK(rec.from_floor > 2000);  // 4513 when written
    CHECK(rec.below > 100);  // the lean sends rays below the floor: the check below is not vacuous
    CHECK(rec.wrong_side == 0);
}
