// Tests of include/glint/photons: photon storage, photon tracing (power conservation on closed
// furnace-like scenes), the left-balanced kd-tree's kNN against brute force, the radiance
// estimate and the surface groups.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <algorithm>
#include <vector>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/photons/photon.hpp>
#include <glint/photons/photon_tracing.hpp>
#include <glint/core/random.hpp>
#include <glint/photons/hash_grid.hpp>
#include <glint/photons/sppm.hpp>
#include <glint/photons/sppm_statistics.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/progressive.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>

using namespace glint;

namespace {

using Accel = MeshBvh<MollerTrumbore<float>, 8>;

/// The closed cube [-1,1]^3, every face Lambertian of grey albedo a facing inwards; the
/// ceiling emits Le when `area_light`, a point light of intensity I sits inside otherwise;
/// `specular` adds a glass sphere and a mirror box (ks = 1), which absorb nothing.
Scene<float> closed_box(float a, bool area_light, bool specular) {
    Scene<float> s;
    s.name = "closed-box";
    const auto wall = s.add_material(Material<float>::lambertian(Rgb<float>(a)));
    const auto ceiling = area_light ? s.add_material(Material<float>::lambertian(Rgb<float>(a), Rgb<float>(2.0f))) : wall;
    using V = Vec3<float>;
    const V o(0);
    detail::add_quad_facing(s, V(-1, -1, -1), V(1, -1, -1), V(1, -1, 1), V(-1, -1, 1), o, wall);
    detail::add_quad_facing(s, V(-1, 1, -1), V(-1, 1, 1), V(1, 1, 1), V(1, 1, -1), o, ceiling);
    detail::add_quad_facing(s, V(-1, -1, -1), V(-1, 1, -1), V(1, 1, -1), V(1, -1, -1), o, wall);
    detail::add_quad_facing(s, V(-1, -1, 1), V(1, -1, 1), V(1, 1, 1), V(-1, 1, 1), o, wall);
    detail::add_quad_facing(s, V(-1, -1, -1), V(-1, -1, 1), V(-1, 1, 1), V(-1, 1, -1), o, wall);
    detail::add_quad_facing(s, V(1, -1, -1), V(1, 1, -1), V(1, 1, 1), V(1, -1, 1), o, wall);
    if (!area_light) s.point_lights.push_back(PointLight<float>::isotropic(V(0.1f, 0.5f, -0.2f), Rgb<float>(1.5f)));
    if (specular) {
        detail::add_sphere(s, V(-0.4f, -0.6f, 0.2f), 0.35f, 12, 24, s.add_material(Material<float>::dielectric(1.5f)));
        detail::add_box(s, V(0.2f, -1.0f, -0.6f), V(0.7f, -0.2f, -0.1f), 0.4f, s.add_material(Material<float>::mirror(Rgb<float>(1.0f))));
    }
    return s;
}

/// Per photon, the luminance of all it stored (global + caustic), over photons 0..N-1.
std::vector<double> stored_per_photon(const Scene<float>& s, const Accel& accel, const PhotonSettings& st) {
    const PhotonEmitters<float> emitters(s);
    std::vector<double> out;
    std::vector<Photon> g, c;
    for (std::size_t i = 0; i < st.photons; ++i) {
        g.clear(), c.clear();
        trace_photon(s, accel, emitters, st, i, g, c);
        double sum = 0;
        for (const Photon& p : g) sum += p.power().luminance();
        for (const Photon& p : c) sum += p.power().luminance();
        out.push_back(sum);
    }
    return out;
}

/// The sum of stored power equals the emitted power times sum_k a^k (k from 0 with the
/// direct hit stored, from 1 without), within 4 standard errors from the measured per-photon
/// variance plus RGBE's rounding bound (2^-8 relative).
void check_conservation(const Scene<float>& s, float a, bool store_direct) {
    const Accel accel(s.triangles);
    const PhotonSettings st{.photons = 20000, .seed = 7, .max_depth = 200, .threads = 1, .store_direct = store_direct};
    const std::vector<double> x = stored_per_photon(s, accel, st);
    double sum = 0, sq = 0;
    for (double v : x) sum += v, sq += v * v;
    const double n = double(x.size()), mean = sum / n, var = (sq / n - mean * mean) * n / (n - 1);
    const double phi = double(PhotonEmitters<float>(s).power().luminance());
    const double expected = phi * (store_direct ? 1.0 : double(a)) / (1.0 - double(a));
    const double tol = 4.0 * std::sqrt(var * n) + expected * 0x1p-8;
    INFO("sum " << sum << " expected " << expected << " tol " << tol);
    CHECK(std::abs(sum - expected) < tol);
    CHECK(tol < 0.05 * expected);  // the test can fail: the tolerance is a few percent
}

}  // namespace

TEST_CASE("photon: RGBE power and quantized direction round trips") {
    const Photon p(Vec3<float>(1, 2, 3), Rgb<float>(0.5f, 0.25f, 0.125f), Vec3<float>(0, 0, -1));
    CHECK(p.power()[0] == doctest::Approx(0.5f).epsilon(1.0 / 256));
    CHECK(p.power()[1] == doctest::Approx(0.25f).epsilon(1.0 / 256));
    CHECK(p.power()[2] == doctest::Approx(0.125f).epsilon(1.0 / 128));
    CHECK(p.direction().z < -0.999f);
    CHECK(Photon(Vec3<float>(0), Rgb<float>(0.0f), Vec3<float>(1, 0, 0)).power().max() == 0.0f);
    // A value whose mantissa rounds up to 256 moves to the next exponent.
    CHECK(Photon(Vec3<float>(0), Rgb<float>(0.9999f), Vec3<float>(1, 0, 0)).power()[0] == doctest::Approx(1.0f));
    Pcg32 rng(3);
    for (int i = 0; i < 1000; ++i) {
        const Vec3<float> d = square_to_uniform_sphere(Vec2<float>(rng.uniform<float>(), rng.uniform<float>()));
        Photon q;
        q.set_direction(d);
        CHECK(glm::dot(q.direction(), d) > std::cos(0.03f));
    }
}

TEST_CASE("photon tracing: stored power is conserved on closed grey boxes") {
    SUBCASE("point light, direct hits stored") { check_conservation(closed_box(0.5f, false, false), 0.5f, true); }
    SUBCASE("point light, direct hits not stored") { check_conservation(closed_box(0.6f, false, false), 0.6f, false); }
    SUBCASE("area light, glass sphere and mirror box") { check_conservation(closed_box(0.5f, true, true), 0.5f, true); }
}

TEST_CASE("photon tracing: L S+ D paths go to the caustic map, independent of the thread count") {
    const Scene<float> s = closed_box(0.5f, false, true);
    const Accel accel(s.triangles);
    PhotonSettings st{.photons = 10000, .seed = 3, .threads = 1};
    const PhotonSet one = trace_photons(s, accel, st);
    st.threads = 3;
    const PhotonSet three = trace_photons(s, accel, st);
    REQUIRE(one.global.size() == three.global.size());
    REQUIRE(one.caustic.size() == three.caustic.size());
    CHECK(std::equal(one.global.begin(), one.global.end(), three.global.begin(), [](const Photon& a, const Photon& b) {
        return a.position == b.position && a.rgbe == b.rgbe && a.theta == b.theta && a.phi == b.phi;
    }));
    CHECK(one.emitted == 10000);
    CHECK(!one.caustic.empty());
    const PhotonSet plain = trace_photons(closed_box(0.5f, false, false), Accel(closed_box(0.5f, false, false).triangles), st);
    CHECK(plain.caustic.empty());
}

TEST_CASE("photon tracing: bad settings and dark scenes are refused") {
    const Scene<float> s = closed_box(0.5f, false, false);
    const Accel accel(s.triangles);
    CHECK_THROWS_WITH_AS(trace_photons(s, accel, PhotonSettings{.photons = 0}), doctest::Contains("got 0"), Error);
    CHECK_THROWS_WITH_AS(trace_photons(s, accel, PhotonSettings{.max_depth = 0}), doctest::Contains("max_depth"), Error);
    Scene<float> dark = s;
    dark.point_lights.clear();
    CHECK_THROWS_WITH_AS(trace_photons(dark, accel, PhotonSettings{}), doctest::Contains("no light"), Error);
}

// ---- the integrators' structures and scenes (photons-render) ----

TEST_CASE("caustic scenes: a closed glass sphere with outward normals, a mirror cube, an area or a point light") {
    for (const char* name : {"cornell-caustics", "cornell-caustics-point"}) {
        const Scene<float> s = builtin_scene<float>(name);
        s.validate();
        CHECK(s.features().specular);
        const bool point = std::string(name).ends_with("point");
        CHECK(s.point_lights.size() == (point ? 1u : 0u));
        CHECK(s.area_lights.size() == (point ? 0u : 1u));
        int glass = 0, mirror = 0;
        double signed_volume = 0;
        const Vec3<double> centre(0.38, 0.335, 0.28);
        for (std::size_t i = 0; i < s.triangles.size(); ++i) {
            const Material<float>& m = s.materials[s.material_of[i]];
            mirror += m.kind == MaterialKind::mirror;
            if (m.kind != MaterialKind::dielectric) continue;
            ++glass;
            CHECK(m.ior == 1.5f);
            const auto& t = s.triangles[i];
            const Vec3<double> a(t[0] - Vec3<float>(centre)), b(t[1] - Vec3<float>(centre)), c(t[2] - Vec3<float>(centre));
            // Outward normal: the centroid is on the normal's positive side of the centre.
            CHECK(glm::dot(Vec3<double>(s.normal(i)), (a + b + c) / 3.0) > 0.0);
            signed_volume += glm::dot(a, glm::cross(b, c)) / 6.0;
        }
        CHECK(glass > 30000);  // finely tessellated
        CHECK(mirror == 12);
        // Closed and outward: the triangles' signed volume is the inscribed polyhedron's.
        CHECK(signed_volume == doctest::Approx(4.0 / 3.0 * pi<double> * std::pow(0.33, 3)).epsilon(0.002));
    }
}

TEST_CASE("hash grid over spheres: every sphere holding a point, as brute force finds them") {
    Pcg32 rng(7, 3);
    std::vector<Vec3<float>> c;
    std::vector<float> r;
    for (int i = 0; i < 2000; ++i) {
        c.emplace_back(rng.uniform<float>() * 4 - 2, rng.uniform<float>() * 4 - 2, rng.uniform<float>() * 0.5f);
        r.push_back(i % 17 == 0 ? 0.0f : 0.01f + 0.2f * rng.uniform<float>());  // some left out
    }
    const SphereHashGrid<float> grid{std::span<const Vec3<float>>(c), std::span<const float>(r)};
    CHECK(grid.cell_size() == doctest::Approx(*std::max_element(r.begin(), r.end())));
    for (int q = 0; q < 3000; ++q) {
        const Vec3<float> p(rng.uniform<float>() * 4.4f - 2.2f, rng.uniform<float>() * 4.4f - 2.2f, rng.uniform<float>() * 0.9f - 0.2f);
        std::vector<std::size_t> got, want;
        grid.query(p, [&](std::size_t i, float d2) {
            got.push_back(i);
            CHECK(d2 < r[i] * r[i]);
        });
        for (std::size_t i = 0; i < c.size(); ++i)
            if (r[i] > 0 && glm::dot(p - c[i], p - c[i]) < r[i] * r[i]) want.push_back(i);
        std::sort(got.begin(), got.end());
        REQUIRE(got == want);  // each once
    }
    // Stress: no spheres, or none with a radius: queries find nothing.
    const SphereHashGrid<float> empty{std::span<const Vec3<float>>(c.data(), 1), std::span<const float>(r.data(), 1)};
    int found = 0;
    empty.query(c[0], [&](std::size_t, float) { ++found; });
    CHECK(found == 0);
}

TEST_CASE("SPPM statistics: the radius shrinks by (N + alpha M) / (N + M), tau scales with the area") {
    SppmStatistics s{0.04, 0.0, Rgb<double>(0.0)};
    s.update(0, Rgb<double>(5.0), 2.0 / 3.0);  // no photon: nothing changes
    CHECK(s.r2 == 0.04);
    CHECK(s.tau[0] == 0.0);
    s.update(30, Rgb<double>(3.0), 2.0 / 3.0);
    CHECK(s.n == doctest::Approx(20.0));
    CHECK(s.r2 == doctest::Approx(0.04 * 20.0 / 30.0));
    CHECK(s.tau[1] == doctest::Approx(3.0 * 20.0 / 30.0));
    s.update(60, Rgb<double>(6.0), 2.0 / 3.0);
    CHECK(s.n == doctest::Approx(60.0));
    CHECK(s.r2 == doctest::Approx(0.04 * 20.0 / 30.0 * 60.0 / 80.0));
    CHECK(s.tau[2] == doctest::Approx((2.0 + 6.0) * 60.0 / 80.0));
    CHECK(s.radiance(2)[0] == doctest::Approx(s.tau[0] / (pi<double> * s.r2 * 2.0)));
    // alpha = 1 keeps the radius and every photon.
    SppmStatistics k{0.01, 0.0, Rgb<double>(0.0)};
    k.update(10, Rgb<double>(1.0), 1.0);
    CHECK(k.r2 == 0.01);
    CHECK_THROWS_AS(check_sppm_alpha(0.0), Error);
    CHECK_THROWS_AS(check_sppm_alpha(1.5), Error);
}

TEST_CASE("progressive passes: the budget's pass count, the mean image and summed statistics") {
    auto pass = [](int k) {
        RenderResult r;
        r.resize(2, 1);
        r.image.at(0, 0) = Rgb<float>(float(k));
        r.variance.at(0, 0) = Rgb<float>(1.0f);
        r.rays = 10;
        return r;
    };
    const ProgressiveResult r = render_passes(PassBudget{0, 4}, pass);
    CHECK(r.passes == 4);
    CHECK(r.image.at(0, 0)[0] == doctest::Approx(1.5));   // (0 + 1 + 2 + 3) / 4
    CHECK(r.variance.at(0, 0)[0] == doctest::Approx(0.25));  // 4 * 1 / 16
    CHECK(r.rays == 40);
    // A time budget stops after the pass that spends it (at least one pass).
    CHECK(render_passes(PassBudget{1e-9, 0}, pass).passes == 1);
    CHECK_THROWS_AS(render_passes(PassBudget{0, 0}, pass), Error);
    CHECK_THROWS_AS(render_passes(PassBudget{-1, 0}, pass), Error);
}

namespace {

/// Per-pixel statistics of two independent renders A and B of the same image against a
/// reference R (with its variance of the mean, Rv), over every pixel and band: the mean
/// squared error of A, the estimated squared bias of (A + B) / 2 (its squared error minus
/// its variance (A - B)^2 / 4 and R's) with that estimate's standard error, and the
/// variance of one render, mean (A - B)^2 / 2; and the bias of the image's mean value, mean
/// ((A + B) / 2 - R), with its standard error (from (A - B)^2 / 4 and Rv).
struct ErrorSplit {
    double mse = 0, bias2 = 0, bias2_se = 0, variance = 0, mean_bias = 0, mean_se = 0;
};

ErrorSplit split_error(const Image<Rgb<float>>& a, const Image<Rgb<float>>& b, const Image<Rgb<float>>& r,
                       const Image<Rgb<float>>& rv) {
    ErrorSplit e;
    double s = 0, s2 = 0;
    const double n = double(a.pixels.size() * 3);
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            const double A = a.pixels[i][c], B = b.pixels[i][c], R = r.pixels[i][c];
            const double d = (A + B) / 2 - R, v = (A - B) * (A - B) / 4;
            const double term = d * d - v - rv.pixels[i][c];
            s += term;
            s2 += term * term;
            e.mse += (A - R) * (A - R) / n;
            e.variance += 2 * v / n;
            e.mean_bias += d / n;
            e.mean_se += (v + rv.pixels[i][c]) / (n * n);
        }
    e.mean_se = std::sqrt(e.mean_se);
    e.bias2 = s / n;
    e.bias2_se = std::sqrt(std::max(0.0, s2 / n - e.bias2 * e.bias2) / n);
    return e;
}

}  // namespace

TEST_CASE("SPPM on the diffuse Cornell box: error against the path tracer falls with passes, bias below the noise") {
    const Scene<float> s = builtin_scene<float>("cornell");
    const Accel accel(s.triangles);
    RenderSettings image;
    image.width = image.height = 12;
    image.pixel_jitter = false;  // fixed rays: both methods estimate the radiance along the same rays
    image.spp = 4096;
    PathTracerSettings<float> pts;
    const RenderResult ref = render_image(s, image, PathTracer<Accel, RandomSampler<float>, MisDirect<float>>(s, accel, pts),
                                          RandomSampler<float>(99));
    const MisDirect<float> direct(s, pts);
    SppmSettings st;
    st.photons = 20000;
    st.radius = 0.15;
    auto run = [&](int passes, std::uint64_t seed) {
        st.seed = seed;
        return render_sppm(s, accel, direct, image, st, PassBudget{0, passes});
    };
    std::vector<ErrorSplit> splits;
    for (int passes : {2, 16, 128}) {
        const SppmResult a = run(passes, 1), b = run(passes, 2);
        CHECK(a.passes == passes);
        splits.push_back(split_error(a.image, b.image, ref.image, ref.variance));
        const ErrorSplit& e = splits.back();
        MESSAGE("SPPM " << passes << " passes: MSE " << e.mse << ", bias^2 " << e.bias2 << " +- " << e.bias2_se
                        << ", variance " << e.variance << ", image mean bias " << e.mean_bias << " +- " << e.mean_se
                        << ", mean radius " << a.mean_radius);
    }
    // Bounds are two standard errors (a 95% band; the seeds are fixed, so the outcome is too).
    // The error falls with passes, and so does the squared bias per pixel.
    CHECK(splits[1].mse < splits[0].mse);
    CHECK(splits[2].mse < splits[1].mse);
    CHECK(splits[2].bias2 + 2 * splits[2].bias2_se < splits[0].bias2 - 2 * splits[0].bias2_se);
    // The first passes' bias (radius 0.15) stands out of their noise, and so does the bias of
    // their image mean (-0.5%); after 128 passes the image mean's bias is within its noise
    // (measured: 1.4 standard errors, 0.03%): a photon power or density normalization off by
    // 0.1% would show.
    CHECK(splits[0].bias2 - 2 * splits[0].bias2_se > 0);
    CHECK(std::abs(splits[0].mean_bias) > 2 * splits[0].mean_se);
    CHECK(std::abs(splits[2].mean_bias) < 2 * splits[2].mean_se);
}

TEST_CASE("SPPM: the same image for any thread count; bad settings are refused before work") {
    const Scene<float> s = builtin_scene<float>("cornell-caustics-point");
    const Accel accel(s.triangles);
    RenderSettings image;
    image.width = image.height = 8;
    const MisDirect<float> direct(s, PathTracerSettings<float>{});
    SppmSettings st;
    st.photons = 3000;
    image.threads = 1;
    const SppmResult one = render_sppm(s, accel, direct, image, st, PassBudget{0, 2});
    image.threads = 3;
    const SppmResult three = render_sppm(s, accel, direct, image, st, PassBudget{0, 2});
    for (std::size_t i = 0; i < one.image.pixels.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) REQUIRE(one.image.pixels[i][c] == three.image.pixels[i][c]);
    SppmSettings bad = st;
    bad.radius = -1;
    CHECK_THROWS_AS(render_sppm(s, accel, direct, image, bad, PassBudget{0, 1}), Error);
    bad = st;
    bad.photons = 0;
    CHECK_THROWS_AS(render_sppm(s, accel, direct, image, bad, PassBudget{0, 1}), Error);
    bad = st;
    bad.alpha = 0;
    CHECK_THROWS_AS(render_sppm(s, accel, direct, image, bad, PassBudget{0, 1}), Error);
}
