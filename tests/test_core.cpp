// Tests for glint/core: exact values, agreement and stress cases.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>
#include <set>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
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
