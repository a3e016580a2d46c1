// Tests for glint/lights: the point emitters' profiles integrate to the power they state, and
// bad lights are rejected by index.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>

#include <glint/lights/light.hpp>
#include <glint/sampling/warps.hpp>

using namespace glint;

namespace {

/// The solid-angle integral of a light's falloff on a fine stratified grid of the sphere.
double integrated_falloff(const PointLight<double>& l) {
    const int n = 1024;
    double sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            sum += l.falloff(square_to_uniform_sphere(Vec2<double>((i + 0.5) / n, (j + 0.5) / n)));
    return sum * 4 * pi<double> / (double(n) * n);
}

}  // namespace

TEST_CASE("each point light's measure() is the integral of its falloff") {
    const Vec3<double> p(0), axis = safe_normalize(Vec3<double>(1, 2, -3));
    const PointLight<double> lights[] = {
        PointLight<double>::isotropic(p, Rgb<double>(1)),
        PointLight<double>::oriented(p, axis, Rgb<double>(1)),
        PointLight<double>::spot(p, axis, Rgb<double>(1), 0.6, 0.3),
        PointLight<double>::spot(p, axis, Rgb<double>(1), 1.2, 1.2),
    };
    for (const auto& l : lights) {
        CAPTURE(int(l.kind));
        // The grid's error is O(1/n) at the cone's edge: 1e-3 relative is 30x what n = 1024 leaves.
        CHECK(integrated_falloff(l) == doctest::Approx(l.measure()).epsilon(1e-3));
        CHECK(l.falloff(-axis) == (l.kind == PointLightKind::isotropic ? 1.0 : 0.0));
    }
}

TEST_CASE("a spot light is I cos(theta) inside its inner cone, dark outside its outer one") {
    const auto s = PointLight<float>::spot(Vec3<float>(0), Vec3<float>(0, 0, -1), Rgb<float>(2), 0.5f, 0.25f);
    CHECK(s.falloff(Vec3<float>(0, 0, -1)) == 1.0f);
    CHECK(s.falloff(Vec3<float>(std::sin(0.2f), 0, -std::cos(0.2f))) == doctest::Approx(std::cos(0.2f)));
    CHECK(s.falloff(Vec3<float>(std::sin(0.55f), 0, -std::cos(0.55f))) == 0.0f);
    const float mid = s.falloff(Vec3<float>(std::sin(0.4f), 0, -std::cos(0.4f)));
    CHECK(mid > 0.0f);
    CHECK(mid < std::cos(0.4f));
    CHECK(s.cos_emission() == doctest::Approx(std::cos(0.5f)));
}

TEST_CASE("invalid point lights are rejected, naming the light") {
    auto l = PointLight<float>::spot(Vec3<float>(0), Vec3<float>(0, 0, 1), Rgb<float>(1), 0.5f, 0.2f);
    CHECK_NOTHROW(l.validate(0));
    l.axis = Vec3<float>(0);
    CHECK_THROWS_WITH_AS(l.validate(7), doctest::Contains("light 7: axis"), Error);
    l = PointLight<float>::isotropic(Vec3<float>(0, NAN, 0), Rgb<float>(1));
    CHECK_THROWS_WITH_AS(l.validate(3), doctest::Contains("light 3: position"), Error);
    l = PointLight<float>::isotropic(Vec3<float>(0), Rgb<float>(-1));
    CHECK_THROWS_WITH_AS(l.validate(2), doctest::Contains("light 2: intensity"), Error);
    l = PointLight<float>::spot(Vec3<float>(0), Vec3<float>(0, 0, 1), Rgb<float>(1), 0.5f, 0.2f);
    std::swap(l.cos_inner, l.cos_outer);
    CHECK_THROWS_WITH_AS(l.validate(1), doctest::Contains("light 1: spot cones"), Error);
}
