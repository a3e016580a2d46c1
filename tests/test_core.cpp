// Tests for glint/core: exact values, agreement and stress cases.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <set>

#include <glint/core/aabb.hpp>
#include <glint/core/camera.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/offset.hpp>
#include <glint/core/random.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>

using namespace glint;

TEST_CASE("exact: PCG32 reproduces the reference sequence of pcg32-demo") {
    // pcg32_srandom(42, 54) then pcg32_random(): the published first outputs of the
    // minimal C implementation's demo.
    Pcg32 rng(42u, 54u);
    const std::uint32_t expected[6] = {0xa15c02b7, 0x7b47f409, 0xba1d3330,
                                       0x83d2f293, 0xbfa4784b, 0xcbed606e};
    for (std::uint32_t e : expected) CHECK(rng.next_u32() == e);
}

TEST_CASE("statistics: PCG32 uniform() lies in [0,1) with mean 1/2 and variance 1/12") {
    Pcg32 rng(7);
    const int n = 1'000'000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        const float u = rng.uniform<float>();
        REQUIRE(u >= 0.0f);
        REQUIRE(u < 1.0f);
        sum += u;
        sum2 += double(u) * u;
    }
    const double mean = sum / n, var = sum2 / n - mean * mean;
    const double se = std::sqrt(var / n);
    CHECK(std::abs(mean - 0.5) < 4 * se);
    CHECK(var == doctest::Approx(1.0 / 12).epsilon(0.01));
}

TEST_CASE("statistics: bounded() is uniform over a non-power-of-two range") {
    Pcg32 rng(3);
    const std::uint32_t bound = 7;
    const int n = 700'000;
    int counts[7] = {};
    for (int i = 0; i < n; ++i) {
        const auto k = rng.bounded(bound);
        REQUIRE(k < bound);
        ++counts[k];
    }
    // Each count is binomial(n, 1/7): allow 5 standard deviations.
    const double p = 1.0 / 7, sd = std::sqrt(n * p * (1 - p));
    for (int c : counts) CHECK(std::abs(c - n * p) < 5 * sd);
}

TEST_CASE("exact: Spectrum arithmetic, max and luminance") {
    Rgb<float> a(1.0f, 0.5f, 0.25f), b(2.0f);
    CHECK((a * b) == Rgb<float>(2.0f, 1.0f, 0.5f));
    CHECK((a + 1.0f) == Rgb<float>(2.0f, 1.5f, 1.25f));
    CHECK((1.0f - a) == Rgb<float>(0.0f, 0.5f, 0.75f));
    CHECK((a / b) == Rgb<float>(0.5f, 0.25f, 0.125f));
    CHECK(a.max() == 1.0f);
    CHECK(a.min() == 0.25f);
    CHECK(max(a, Rgb<float>(0.0f, 1.0f, 0.0f)) == Rgb<float>(1.0f, 1.0f, 0.25f));
    // 000 section 2.2 weights; grey input gives its value back (weights sum to 1).
    CHECK(Rgb<double>(1.0).luminance() == doctest::Approx(1.0).epsilon(1e-12));
    CHECK(Rgb<double>(0.0, 1.0, 0.0).luminance() == doctest::Approx(0.6094));
    CHECK(a.luminance(Rgb<float>(1.0f, 0.0f, 0.0f)) == 1.0f);
    Spectrum<double, 8> s(2.0);
    CHECK(s.luminance() == doctest::Approx(2.0));
    CHECK(s.mean() == doctest::Approx(2.0));
    CHECK(Spectrum<float, 4>(0.0f).is_zero());
    CHECK_FALSE(Rgb<float>(0.0f, std::nanf(""), 0.0f).is_finite());
}

TEST_CASE("exact: orthonormal basis is orthonormal, including at the poles") {
    Pcg32 rng(11);
    std::vector<Vec3d> normals = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}};
    for (int i = 0; i < 1000; ++i)
        normals.push_back(safe_normalize(Vec3d(rng.uniform<double>() - 0.5,
                                               rng.uniform<double>() - 0.5,
                                               rng.uniform<double>() - 0.5)));
    for (const Vec3d& n : normals) {
        Vec3d b1, b2;
        orthonormal_basis(n, b1, b2);
        CHECK(glm::length(b1) == doctest::Approx(1.0).epsilon(1e-12));
        CHECK(glm::length(b2) == doctest::Approx(1.0).epsilon(1e-12));
        CHECK(std::abs(glm::dot(b1, n)) < 1e-12);
        CHECK(std::abs(glm::dot(b2, n)) < 1e-12);
        CHECK(std::abs(glm::dot(b1, b2)) < 1e-12);
        CHECK(glm::dot(glm::cross(b1, b2), n) == doctest::Approx(1.0).epsilon(1e-12));
    }
}

TEST_CASE("stress: safe_normalize never returns NaN") {
    const Vec3f fb(0, 1, 0);
    CHECK(safe_normalize(Vec3f(0.0f), fb) == fb);
    CHECK(safe_normalize(Vec3f(std::nanf(""), 0, 0), fb) == fb);
    CHECK(safe_normalize(Vec3f(infinity<float>, 0, 0), fb) == fb);
    CHECK(safe_normalize(Vec3f(3, 0, 4)).x == doctest::Approx(0.6f));
    CHECK(max_abs_axis(Vec3f(-5, 2, 3)) == 0);
    CHECK(max_abs_axis(Vec3f(1, -2, 1)) == 1);
    CHECK(max_abs_axis(Vec3f(1, 2, -3)) == 2);
}

TEST_CASE("exact and stress: AABB slab test") {
    AABB<float> box;
    CHECK(box.empty());
    box.extend(Vec3f(-1, -1, -1));
    box.extend(Vec3f(1, 1, 1));
    CHECK_FALSE(box.empty());
    CHECK(box.surface_area() == 24.0f);
    CHECK(box.contains(Vec3f(0)));

    auto hit = [&](Ray<float> r, float& t0, float& t1) {
        return box.intersect(r, 1.0f / r.direction, t0, t1);
    };
    float t0, t1;
    Ray<float> r{{-3, 0, 0}, {1, 0, 0}};
    REQUIRE(hit(r, t0, t1));
    CHECK(t0 == 2.0f);
    CHECK(t1 == 4.0f);
    // Parallel to a slab, outside it: miss; inside it: hit.
    CHECK_FALSE(hit(Ray<float>{{-3, 2, 0}, {1, 0, 0}}, t0, t1));
    CHECK(hit(Ray<float>{{-3, 0.5f, 0}, {1, 0, 0}}, t0, t1));
    // Ray inside the box: entry clamps to tmin.
    REQUIRE(hit(Ray<float>{{0, 0, 0}, {0, 0, 1}}, t0, t1));
    CHECK(t0 == 0.0f);
    CHECK(t1 == 1.0f);
    // Interval ends before the box.
    CHECK_FALSE(hit(Ray<float>{{-3, 0, 0}, {1, 0, 0}, 0.0f, 1.5f}, t0, t1));
    // A ray lying in a face plane (0 * inf = NaN in that slab) is kept: conservative.
    CHECK(hit(Ray<float>{{-3, 1, 0}, {1, 0, 0}}, t0, t1));
    CHECK(hit(Ray<float>{{-3, 1, 0}, {1, -0.0f, 0}}, t0, t1));  // negative zero: 1/d = -inf
    CHECK(hit(Ray<float>{{3, -1, 0}, {-1, -0.0f, 0}}, t0, t1));
    CHECK_FALSE(hit(Ray<float>{{-3, 1.5f, 0}, {1, -0.0f, 0}}, t0, t1));
}

TEST_CASE("glint::Error carries its message") {
    try {
        throw Error("scene.obj:12: expected 3 vertex indices");
    } catch (const std::exception& e) {
        CHECK(std::string(e.what()) == "scene.obj:12: expected 3 vertex indices");
    }
}

#include <glint/version.hpp>

TEST_CASE("version: the string is the three numbers") {
    CHECK(std::to_string(glint::version_major) + "." + std::to_string(glint::version_minor) + "." +
              std::to_string(glint::version_patch) ==
          glint::version_string);
}

TEST_CASE("offset: a ray leaving a far-off triangle starts strictly on the side it leaves to") {
    // A triangle far from the origin, where o + t d would err by many ulps: the interpolated
    // point, moved past its error bound, lies on the requested side of the exact plane.
    const std::array<glint::Vec3<float>, 3> tri{glint::Vec3<float>(1e4f, 2e4f, -3e4f),
                                                glint::Vec3<float>(1e4f + 1, 2e4f, -3e4f + 0.5f),
                                                glint::Vec3<float>(1e4f, 2e4f + 1, -3e4f + 0.25f)};
    const glint::Vec3d e1 = glint::Vec3d(tri[1]) - glint::Vec3d(tri[0]), e2 = glint::Vec3d(tri[2]) - glint::Vec3d(tri[0]);
    const glint::Vec3d nd = glm::normalize(glm::cross(e1, e2));
    const glint::Vec3<float> n(nd);
    glint::Pcg32 rng(5);
    int wrong = 0;
    for (int i = 0; i < 1000; ++i) {
        const float u = rng.uniform<float>() * 0.5f, v = rng.uniform<float>() * 0.5f;
        const glint::SurfacePoint<float> p = glint::surface_point(tri, u, v);
        CHECK(p.err.x > 0);
        for (float side : {1.f, -1.f}) {
            const glint::Vec3<float> o = glint::offset_origin(p.x, p.err, n, n * side);
            const double h = glm::dot(glint::Vec3d(o) - glint::Vec3d(tri[0]), nd);  // signed distance, in double
            wrong += !(h * side > 0);
        }
    }
    CHECK(wrong == 0);
}

TEST_CASE("camera: the film centre looks at the target, the top left corner up and to the left") {
    const glint::Camera<double> cam{{1, 2, 3}, {1, 2, -7}, {0, 1, 0}, 1.0};
    const auto c = cam.ray(0.5, 0.5, 2.0);
    CHECK(glm::length(c.direction - glint::Vec3d(0, 0, -1)) < 1e-12);
    const auto tl = cam.ray(0, 0, 2.0);
    CHECK(tl.direction.y / -tl.direction.z == doctest::Approx(std::tan(0.5)));
    CHECK(tl.direction.x / -tl.direction.z == doctest::Approx(-2 * std::tan(0.5)));
    CHECK(tl.origin == cam.eye);
}
