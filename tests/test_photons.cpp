// Tests of include/glint/photons: photon storage, photon tracing (power conservation on closed
// furnace-like scenes), the left-balanced kd-tree's kNN against brute force, the radiance
// estimate and the surface groups.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/photons/photon.hpp>
#include <glint/photons/photon_tracing.hpp>
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
