// Tests of glint/cones: incremental enclosing cones (000 section 6.2), minimal enclosing
// spheres and the cone-sphere test (000 section 6.3.4), the ray-tile engine (000 section 6.3)
// against brute force.
//
// exact:     the repaired formulas of 000 section 6.2 and 6.3.4 on hand-derived cases; the
//            printed translation formula moves the apex the wrong way (documented repair).
// agreement: every ray of every bundle lies inside its cone (checked in long double);
//            the cone-sphere test never culls a sphere the exact test keeps; every hit of
//            every pass of the ray-tile engine is bit-for-bit the brute-force hit.
// stress:    identical rays, zero spread, nearly opposite directions, incoherent bundles,
//            NaN / infinite / zero rays, degenerate triangles: no NaN, fallback cones.
// CI sizes; -DGLINT_LONG_TESTS runs more bundles and larger images.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <vector>

#include <glint/cones/cone.hpp>
#include <glint/cones/glass.hpp>
#include <glint/cones/ray_tiles.hpp>
#include <glint/cones/sphere.hpp>
#include <glint/core/random.hpp>
#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/trees/brute_force.hpp>
#include "tree_scenes.hpp"

using namespace glint;

namespace {

#ifdef GLINT_LONG_TESTS
constexpr int bundles_per_kind = 20000;
constexpr int image_size = 128;
#else
constexpr int bundles_per_kind = 600;
constexpr int image_size = 48;
#endif

using LD = long double;
using Vec3L = glm::vec<3, LD, glm::defaultp>;

template <class T>
Vec3L to_ld(const Vec3<T>& v) {
    return Vec3L(LD(v.x), LD(v.y), LD(v.z));
}

LD len(const Vec3L& v) { return std::sqrt(glm::dot(v, v)); }

/// Exact (long double) distance from p to the ideal cone (apex, axis, half angle) stored in
/// `c` (0 inside).
template <class T>
LD distance_to_cone(const Cone<T>& c, const Vec3L& p) {
    const Vec3L a = to_ld(c.apex), x = to_ld(c.axis) / len(to_ld(c.axis));
    const Vec3L w = p - a;
    const LD h = glm::dot(w, x), rho = len(glm::cross(w, x));
    const LD cs = LD(c.cos_half), sn = LD(c.sin_half);
    const LD n = std::sqrt(cs * cs + sn * sn);  // cos/sin as stored, as an angle
    if (rho * sn + h * cs >= 0) return std::max(LD(0), (rho * cs - h * sn) / n);
    return len(w);
}

/// Whether the direction d lies within the opening (exact, long double).
template <class T>
bool direction_inside(const Cone<T>& c, const Vec3<T>& d) {
    const Vec3L u = to_ld(d) / len(to_ld(d)), x = to_ld(c.axis) / len(to_ld(c.axis));
    const LD cs = LD(c.cos_half), sn = LD(c.sin_half);
    // angle(u, x) <= phi  <=>  cross part * cos - dot part * sin <= 0 (phi <= 90 degrees).
    return len(glm::cross(u, x)) * cs - glm::dot(u, x) * sn <= 0;
}

/// Every ray that can hit lies inside the cone: direction within the opening, origin and
/// points along the ray within `slack` of the ideal cone. Also no NaN anywhere.
template <class T>
void check_encloses(const Cone<T>& c, std::span<const Ray<T>> rays) {
    REQUIRE(all_finite(c.apex));
    REQUIRE(all_finite(c.axis));
    REQUIRE(std::isfinite(c.cos_half));
    REQUIRE(std::isfinite(c.sin_half));
    REQUIRE(std::isfinite(c.slack));
    REQUIRE(c.slack >= T(0));
    if (c.all) return;
    REQUIRE(c.half_angle <= T(pi<double> / 2));
    REQUIRE(std::abs(glm::length(c.axis) - T(1)) < T(1e-5));
    for (const Ray<T>& r : rays) {
        if (!ray_can_hit(r)) continue;
        REQUIRE(direction_inside(c, r.direction));
        const Vec3L o = to_ld(r.origin), d = to_ld(r.direction) / len(to_ld(r.direction));
        REQUIRE(distance_to_cone(c, o) <= LD(c.slack));
        for (LD t : {LD(0.5), LD(3), LD(100)})
            REQUIRE(distance_to_cone(c, o + t * d) <= LD(c.slack) * (1 + LD(1e-12)) + LD(1e-15) * len(o + t * d));
    }
}

template <class T>
Vec3<T> random_unit(Pcg32& rng) {
    const double z = 2 * rng.uniform<double>() - 1, ph = 2 * pi<double> * rng.uniform<double>();
    const double s = std::sqrt(std::max(0.0, 1 - z * z));
    return Vec3<T>(Vec3d(s * std::cos(ph), s * std::sin(ph), z));
}

/// Direction within `spread` radians of `axis` (uniform in angle and azimuth).
template <class T>
Vec3<T> around(Pcg32& rng, const Vec3d& axis, double spread) {
    Vec3d b1, b2;
    orthonormal_basis(axis, b1, b2);
    const double th = spread * rng.uniform<double>(), ph = 2 * pi<double> * rng.uniform<double>();
    return Vec3<T>(std::cos(th) * axis + std::sin(th) * (std::cos(ph) * b1 + std::sin(ph) * b2));
}

/// A bundle of n rays: origins within `size` of a random centre (scale `far` from the
/// world origin), directions within `spread` of a random axis.
template <class T>
std::vector<Ray<T>> bundle(Pcg32& rng, int n, double size, double spread, double far = 1.0) {
    // One draw per statement: the order of two calls in one expression is unspecified, and
    // GCC and clang would draw different cases.
    const Vec3d centre_dir = Vec3d(random_unit<double>(rng));
    const Vec3d centre = centre_dir * far * rng.uniform<double>();
    const Vec3d axis = Vec3d(random_unit<double>(rng));
    std::vector<Ray<T>> rays(n);
    for (auto& r : rays) {
        const Vec3d offset_dir = Vec3d(random_unit<double>(rng));
        r.origin = Vec3<T>(centre + size * offset_dir * rng.uniform<double>());
        r.direction = around<T>(rng, axis, spread);
    }
    return rays;
}

template <class T>
void check_kind(Pcg32& rng, double size, double spread, double far, ConeOrder order, bool expect_narrow) {
    ConeOptions opt;
    opt.order = order;
    int narrow = 0;
    for (int b = 0; b < bundles_per_kind; ++b) {
        const int n = 1 + int(rng.bounded(256));
        const auto rays = bundle<T>(rng, n, size, spread, far);
        const Cone<T> c = enclosing_cone(std::span<const Ray<T>>(rays), opt);
        check_encloses(c, std::span<const Ray<T>>(rays));
        narrow += !c.all && c.half_angle <= T(2 * spread + 0.1);
    }
    if (expect_narrow) CHECK(narrow >= bundles_per_kind * 9 / 10);
}

}  // namespace

TEST_CASE("exact: widening the cone to a direction (000 section 6.2, step a)") {
    // Zero-angle cone along z; a direction at 60 degrees in the xz plane: the new cone is
    // the bisector, axis at 30 degrees, half angle 30 degrees; 000's e + r form agrees.
    detail::ConeState<double> s;
    s.axis = Vec3d(0, 0, 1);
    const double th = pi<double> / 3;
    const Vec3d r(std::sin(th), 0, std::cos(th));
    detail::extend_to_direction(s, r, ConeOptions{});
    CHECK(s.phi == doctest::Approx(pi<double> / 6).epsilon(1e-12));
    CHECK(s.axis.x == doctest::Approx(0.5).epsilon(1e-12));
    CHECK(s.axis.z == doctest::Approx(std::sqrt(3.0) / 2).epsilon(1e-12));
    // 000's formulas from an existing cone (axis z, phi = 20 deg) and r at 70 degrees.
    detail::ConeState<double> t;
    t.axis = Vec3d(0, 0, 1);
    t.set_phi(pi<double> / 9);
    const double th2 = 7 * pi<double> / 18;
    const Vec3d r2(std::sin(th2), 0, std::cos(th2));
    const Vec3d x = t.axis;
    const Vec3d q = glm::normalize(glm::dot(x, r2) * x - r2);
    const Vec3d e = x * t.cos_phi + q * t.sin_phi;
    const Vec3d x_new = glm::normalize(e + r2);
    detail::extend_to_direction(t, r2, ConeOptions{});
    CHECK(glm::length(t.axis - x_new) < 1e-12);
    CHECK(std::cos(t.phi) == doctest::Approx(glm::dot(x_new, r2)).epsilon(1e-12));
    // A direction already inside changes nothing.
    const detail::ConeState<double> before = t;
    detail::extend_to_direction(t, t.axis, ConeOptions{});
    CHECK(t.phi == before.phi);
}

TEST_CASE("exact: translating the apex to an origin (000 section 6.2, step b; sign repaired)") {
    detail::ConeState<double> s;
    s.axis = Vec3d(0, 0, 1);
    s.set_phi(pi<double> / 6);
    const Vec3d o(1, 0, 0);
    // Derived: s = |g| / sin(2 phi) = cos 30 / sin 60 = 1 along e = (-1/2, 0, sqrt(3)/2):
    // the apex moves back to (1/2, 0, -sqrt(3)/2) and o lies on the near generator.
    detail::translate_to_point(s, o, ConeOptions{});
    CHECK(s.apex.x == doctest::Approx(0.5).epsilon(1e-5));
    CHECK(s.apex.z == doctest::Approx(-std::sqrt(3.0) / 2).epsilon(1e-5));
    const Vec3d v = glm::normalize(o - s.apex);
    CHECK(v.x == doctest::Approx(0.5).epsilon(1e-5));
    // The formula as printed, t = g^2 / (e . g), a_new = a - e t, moves the apex forwards
    // and leaves o outside: the repair is needed.
    const Vec3d x(0, 0, 1), q = glm::normalize(glm::dot(x, o) * x - o);
    const double cp = std::cos(pi<double> / 6), sp = std::sin(pi<double> / 6);
    const Vec3d e = x * cp + q * sp, n = x * cp - q * sp;
    const Vec3d g = o - glm::dot(n, o) * n;
    const double t = glm::dot(g, g) / glm::dot(e, g);
    const Vec3d printed = Vec3d(0) - e * t;
    const Vec3d w = o - printed;
    CHECK(glm::length(glm::cross(w, x)) * cp - glm::dot(w, x) * sp > 0.1);  // outside
    // o behind the apex, on the axis: the apex moves back to o (axis translation).
    detail::ConeState<double> b;
    b.axis = Vec3d(0, 0, 1);
    b.set_phi(0.2);
    detail::translate_to_point(b, Vec3d(0, 0, -3), ConeOptions{});
    CHECK(b.apex.z <= -3.0);
    CHECK(b.apex.z > -3.0001);
    // o behind the apex and off the axis (h sin phi + rho cos phi < 0): translation along e
    // would put o on the backward half of the near generator; the result holds o.
    detail::ConeState<double> c;
    c.axis = Vec3d(0, 0, 1);
    c.set_phi(pi<double> / 6);
    detail::translate_to_point(c, Vec3d(1, 0, -10), ConeOptions{});
    const Vec3d wc = Vec3d(1, 0, -10) - c.apex;
    CHECK(glm::length(glm::cross(wc, c.axis)) * c.cos_phi - glm::dot(wc, c.axis) * c.sin_phi <= 1e-12);
}

TEST_CASE("exact: cone-sphere test (000 section 6.3.4, normalization repaired)") {
    Cone<double> c;
    c.apex = Vec3d(0);
    c.axis = Vec3d(0, 0, 1);
    c.half_angle = pi<double> / 6;
    c.cos_half = std::cos(c.half_angle);
    c.sin_half = std::sin(c.half_angle);
    // Centre at 45 degrees, distance 10: it meets the 30-degree cone when its angular radius
    // exceeds 15 degrees, r > 10 sin 15 = 2.588.
    const Vec3d v(10 * std::sin(pi<double> / 4), 0, 10 * std::cos(pi<double> / 4));
    CHECK(cone_meets_sphere(c, BoundingSphere<double>{v, 2.6}));
    CHECK_FALSE(cone_meets_sphere(c, BoundingSphere<double>{v, 2.58}));
    // The repaired angle form agrees: phi > arccos((v - a) . x / |v - a|) - arcsin(r / |v - a|).
    for (double r : {2.0, 2.58, 2.6, 5.0}) {
        const double d = glm::length(v);
        const bool angle_form = c.half_angle > std::acos(v.z / d) - std::asin(r / d);
        CHECK(cone_meets_sphere(c, BoundingSphere<double>{v, r}) == angle_form);
    }
    // Behind the apex: only when the sphere holds the apex (d < r, arcsin undefined).
    CHECK_FALSE(cone_meets_sphere(c, BoundingSphere<double>{Vec3d(0, 0, -5), 4.9}));
    CHECK(cone_meets_sphere(c, BoundingSphere<double>{Vec3d(0, 0, -5), 5.1}));
    // Inside the cone, far along the axis; the cone that admits everything; empty sphere.
    CHECK(cone_meets_sphere(c, BoundingSphere<double>{Vec3d(0, 0, 1e6), 1e-9}));
    CHECK(cone_meets_sphere(Cone<double>::everything(), BoundingSphere<double>{Vec3d(0, 0, -5), 0.1}));
    CHECK_FALSE(cone_meets_sphere(c, BoundingSphere<double>{Vec3d(0, 0, 1), -1.0}));
}

TEST_CASE("exact: minimal enclosing sphere of a triangle") {
    // Right triangle: the hypotenuse is a diameter.
    auto s = min_enclosing_sphere<double>({Vec3d(0, 0, 0), Vec3d(2, 0, 0), Vec3d(0, 2, 0)});
    CHECK(glm::length(s.center - Vec3d(1, 1, 0)) < 1e-12);
    CHECK(s.radius == doctest::Approx(std::sqrt(2.0)).epsilon(1e-12));
    // Equilateral: the circumcentre, r = side / sqrt(3).
    s = min_enclosing_sphere<double>({Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0.5, std::sqrt(3.0) / 2, 0)});
    CHECK(s.radius == doctest::Approx(1 / std::sqrt(3.0)).epsilon(1e-12));
    // Obtuse: the longest edge is a diameter (smaller than the circumsphere).
    s = min_enclosing_sphere<double>({Vec3d(0, 0, 0), Vec3d(4, 0, 0), Vec3d(2, 0.5, 0)});
    CHECK(glm::length(s.center - Vec3d(2, 0, 0)) < 1e-12);
    CHECK(s.radius == doctest::Approx(2).epsilon(1e-12));
    // Degenerate: collinear, repeated vertex, all equal; non-finite gives the empty sphere.
    s = min_enclosing_sphere<double>({Vec3d(0, 0, 0), Vec3d(1, 1, 1), Vec3d(3, 3, 3)});
    CHECK(s.radius == doctest::Approx(std::sqrt(27.0) / 2).epsilon(1e-12));
    s = min_enclosing_sphere<double>({Vec3d(1, 2, 3), Vec3d(1, 2, 3), Vec3d(1, 2, 5)});
    CHECK(s.radius == doctest::Approx(1).epsilon(1e-12));
    s = min_enclosing_sphere<double>({Vec3d(1, 2, 3), Vec3d(1, 2, 3), Vec3d(1, 2, 3)});
    CHECK(s.radius >= 0.0);
    CHECK(s.radius < 1e-12);
    s = min_enclosing_sphere<double>({Vec3d(0), Vec3d(std::nan(""), 0, 0), Vec3d(1, 0, 0)});
    CHECK(s.radius < 0.0);
    CHECK_FALSE(cone_meets_sphere(Cone<double>{}, s));
}

TEST_CASE("agreement: enclosing spheres hold their triangles and are minimal (float, far from the origin)") {
    Pcg32 rng(5);
    for (int i = 0; i < 20000; ++i) {
        const double far = i % 2 ? 1e4 : 1.0;
        const Vec3d c = Vec3d(random_unit<double>(rng)) * far;
        TriangleVertices<float> t;
        for (auto& v : t) v = Vec3f(c + Vec3d(random_unit<double>(rng)) * rng.uniform<double>());
        const auto s = min_enclosing_sphere(t);
        double longest = 0;
        for (int k = 0; k < 3; ++k) {
            REQUIRE(glm::length(to_ld(t[k]) - to_ld(s.center)) <= LD(s.radius));
            longest = std::max(longest, glm::length(Vec3d(t[k]) - Vec3d(t[(k + 1) % 3])));
        }
        // Minimal: no sphere smaller than half the longest edge holds it; the circumsphere
        // is never smaller than the minimal sphere.
        REQUIRE(double(s.radius) >= 0.5 * longest * (1 - 1e-6));
        REQUIRE(double(s.radius) <= 0.5 * longest / std::sin(pi<double> / 3) * (1 + 1e-5) + 1e-6 * far);
    }
}

TEST_CASE("agreement: every ray of random coherent bundles lies inside its cone") {
    Pcg32 rng(17);
    for (ConeOrder order : {ConeOrder::directions_first, ConeOrder::interleaved}) {
        CAPTURE(int(order));
        check_kind<float>(rng, 0.05, 0.05, 1.0, order, true);
        check_kind<double>(rng, 0.05, 0.05, 1.0, order, true);
        check_kind<float>(rng, 0.5, 0.3, 1.0, order, false);
        check_kind<float>(rng, 1e-3, 0.01, 1e4, order, true);  // far from the origin
        check_kind<double>(rng, 2.0, 0.01, 1e6, order, false);
    }
}

TEST_CASE("agreement: directions first gives narrower cones than 000's interleaved order") {
    Pcg32 rng(23);
    double wide_a = 0, wide_b = 0;
    for (int b = 0; b < 200; ++b) {
        const auto rays = bundle<float>(rng, 256, 0.05, 0.1);
        ConeOptions o1, o2;
        o2.order = ConeOrder::interleaved;
        const auto c1 = enclosing_cone(std::span<const Ray<float>>(rays), o1);
        const auto c2 = enclosing_cone(std::span<const Ray<float>>(rays), o2);
        // Width of the cone at the rays' centre: distance from apex times tan(phi).
        const Vec3f centre = rays[0].origin;
        wide_a += glm::length(centre - c1.apex) * std::tan(double(c1.half_angle));
        wide_b += glm::length(centre - c2.apex) * std::tan(double(c2.half_angle));
    }
    MESSAGE("mean cone radius at the rays: directions first " << wide_a / 200 << ", interleaved " << wide_b / 200);
    CHECK(wide_a <= wide_b);
}

TEST_CASE("stress: degenerate bundles (identical rays, zero spread, nearly opposite, incoherent)") {
    Pcg32 rng(29);
    const auto check = [](const std::vector<Ray<float>>& rays) {
        for (ConeOrder order : {ConeOrder::directions_first, ConeOrder::interleaved}) {
            ConeOptions opt;
            opt.order = order;
            const Cone<float> c = enclosing_cone(std::span<const Ray<float>>(rays), opt);
            check_encloses(c, std::span<const Ray<float>>(rays));
        }
        return enclosing_cone(std::span<const Ray<float>>(rays));
    };
    for (int b = 0; b < 50; ++b) {
        // Identical rays: a zero-width cone (a few ulps) at the origin.
        Ray<float> r;
        r.origin = Vec3f(random_unit<float>(rng)) * 3.0f;
        r.direction = random_unit<float>(rng);
        const Cone<float> same = check(std::vector<Ray<float>>(64, r));
        CHECK_FALSE(same.all);
        CHECK(same.half_angle < 1e-5f);
        // Zero spread: parallel rays from a disc (orthographic camera): a narrow cone
        // (min_translate_angle) with a distant apex.
        std::vector<Ray<float>> par(256, r);
        Vec3f b1, b2;
        orthonormal_basis(r.direction, b1, b2);
        for (int k = 0; k < 256; ++k) par[k].origin += 0.01f * float(k % 16) * b1 + 0.01f * float(k / 16) * b2;
        const Cone<float> p = check(par);
        CHECK_FALSE(p.all);
        CHECK(p.half_angle < 0.01f);
        // Same origin, spread directions: apex at the origin.
        std::vector<Ray<float>> fan(256, r);
        for (auto& f : fan) f.direction = around<float>(rng, Vec3d(r.direction), 0.2);
        const Cone<float> fc = check(fan);
        CHECK(glm::length(fc.apex - r.origin) < 1e-5f);
        // Nearly opposite directions: no cone below 90 degrees holds them: the fallback.
        std::vector<Ray<float>> opp(2, r);
        opp[1].direction = -r.direction + 1e-4f * b1;
        opp[1].origin += 1e-3f * b2;
        CHECK(check(opp).all);
        std::vector<Ray<float>> exact_opp(2, r);
        exact_opp[1].direction = -r.direction;
        CHECK(check(exact_opp).all);
        // Incoherent: directions over the whole sphere.
        std::vector<Ray<float>> inc(64);
        for (auto& ir : inc) {
            ir.origin = random_unit<float>(rng);
            ir.direction = random_unit<float>(rng);
        }
        CHECK(check(inc).all);
    }
    // Rays that cannot hit (NaN, infinite, zero direction) are skipped; tiny directions are
    // not (they can hit at huge t).
    std::vector<Ray<float>> odd(6);
    odd[0].origin = Vec3f(std::nanf(""), 0, 0);
    odd[1].direction = Vec3f(0, 0, 0);
    odd[2].direction = Vec3f(infinity<float>, 0, 1);
    odd[3].origin = Vec3f(1, 2, 3);
    odd[3].direction = Vec3f(1e-30f, 0, 0);
    odd[4].origin = Vec3f(1, 2, 3.5f);
    odd[4].direction = Vec3f(1, 1e-3f, 0);
    odd[5].origin = Vec3f(-infinity<float>, 0, 0);
    const Cone<float> oc = check(odd);
    CHECK_FALSE(oc.all);
    // No ray can hit: a finite cone (never consulted).
    const Cone<float> none = check(std::vector<Ray<float>>{odd[0], odd[1], odd[2]});
    CHECK(all_finite(none.apex));
    // Bad options throw.
    ConeOptions bad;
    bad.max_half_angle = 2.0;
    CHECK_THROWS_AS(enclosing_cone(std::span<const Ray<float>>(odd), bad), Error);
    bad = ConeOptions{};
    bad.min_translate_angle = 0;
    CHECK_THROWS_AS(enclosing_cone(std::span<const Ray<float>>(odd), bad), Error);
}

TEST_CASE("agreement: the cone-sphere test never culls a sphere the exact test keeps") {
    Pcg32 rng(31);
    int kept = 0, culled = 0;
    for (int i = 0; i < 200000; ++i) {
        const auto rays = bundle<float>(rng, 8, 0.1, 0.2, i % 3 ? 1.0 : 1e3);
        const Cone<float> c = enclosing_cone(std::span<const Ray<float>>(rays));
        if (c.all) continue;
        BoundingSphere<float> s;
        const Vec3d dir = Vec3d(around<double>(rng, Vec3d(c.axis), 1.2 * double(c.half_angle) + 0.05));
        s.center = Vec3f(Vec3d(c.apex) + dir * (4.0 * rng.uniform<double>() - 0.5) * glm::length(Vec3d(c.apex) + 1.0));
        s.radius = float(0.1 * rng.uniform<double>());
        // Exact in long double: distance from the centre to the ideal cone versus r + slack.
        const LD dist = distance_to_cone(c, to_ld(s.center));
        const bool exact = dist <= LD(s.radius) + LD(c.slack);
        const bool test = cone_meets_sphere(c, s);
        if (exact) REQUIRE(test);
        if (exact) ++kept;
        // It culls: spheres clearly away from the cone are rejected. "Clearly" is beyond the
        // enlargement the test documents (cone_test_radius and cone_meets_sphere: the slack
        // plus 16 eps (|centre| + |apex|) plus 16 eps (rho + |h|) <= 16 (1 + sqrt 2) eps
        // (|centre| + |apex|)), plus 0.1%: with the apex 10^3 from the origin that rounding
        // bound is about 2e-3, larger than a relative margin alone.
        const LD rounding = 40 * LD(std::numeric_limits<float>::epsilon()) * (len(to_ld(s.center)) + len(to_ld(c.apex)));
        if (dist > (LD(s.radius) + LD(c.slack) + rounding) * 1.001L + 1e-4L * len(to_ld(s.center) - to_ld(c.apex))) {
            CHECK_FALSE(test);
            ++culled;
        }
    }
    MESSAGE("kept " << kept << ", culled " << culled);
    CHECK(kept > 1000);
    CHECK(culled > 1000);
}

TEST_CASE("exact: refraction and total internal reflection") {
    Vec3d out;
    CHECK(refract_or_reflect(Vec3d(0, 0, -1), Vec3d(0, 0, 1), 1.0, 1.5, out));
    CHECK(glm::length(out - Vec3d(0, 0, -1)) < 1e-12);
    // Snell: sin t = sin i / 1.5.
    const double i = 0.7;
    CHECK(refract_or_reflect(Vec3d(std::sin(i), 0, -std::cos(i)), Vec3d(0, 0, 1), 1.0, 1.5, out));
    CHECK(out.x == doctest::Approx(std::sin(i) / 1.5).epsilon(1e-12));
    CHECK(out.z < 0);
    // Leaving the glass beyond the critical angle asin(1/1.5) = 41.8 deg: mirror.
    const double j = 0.8;
    CHECK_FALSE(refract_or_reflect(Vec3d(std::sin(j), 0, std::cos(j)), Vec3d(0, 0, 1), 1.0, 1.5, out));
    CHECK(glm::length(out - Vec3d(std::sin(j), 0, -std::cos(j))) < 1e-12);
    // Leaving below it: refracted out, sin t = 1.5 sin i.
    const double k = 0.5;
    CHECK(refract_or_reflect(Vec3d(std::sin(k), 0, std::cos(k)), Vec3d(0, 0, 1), 1.0, 1.5, out));
    CHECK(out.x == doctest::Approx(1.5 * std::sin(k)).epsilon(1e-12));
}

namespace {

/// Runs the glass passes with the engine and with brute force and requires every hit of
/// every pass to be identical. Returns the engine's counts.
template <class P>
PassStats compare_passes(const Mesh<typename P::scalar_type>& mesh, std::vector<Ray<typename P::scalar_type>> rays,
                         const TileGrid& grid, int passes, const TileOptions& opt = TileOptions{}) {
    using T = typename P::scalar_type;
    const std::span<const TriangleVertices<T>> tris(mesh);
    const RayTileEngine<P> engine(tris, opt);
    const BruteForce<P> brute(tris);
    const AABB<T> box = mesh_bounds(tris);
    const GlassShader<T> glass(tris, T(1.5), T(1e-4) * glm::length(box.extent()));
    struct Rec {
        std::size_t i;
        StoreHit<T> h;
        bool found;
    };
    std::vector<Rec> a, b;
    auto recorder = [&](std::vector<Rec>& out) {
        return [&out, &glass](std::size_t i, Ray<T>& r, const StoreHit<T>& h, bool found) {
            out.push_back({i, h, found});
            return glass(i, r, h, found);
        };
    };
    std::vector<Ray<T>> r1 = rays, r2 = rays;
    TileWorkspace<T> w1, w2;
    const PassStats s1 = engine.trace_passes(std::span<Ray<T>>(r1), grid, passes, recorder(a), w1);
    const PassStats s2 = trace_passes(brute, std::span<Ray<T>>(r2), passes, recorder(b), w2);
    REQUIRE(a.size() == b.size());
    std::size_t mismatches = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
        const bool same = a[k].i == b[k].i && a[k].found == b[k].found &&
                          (!a[k].found || (a[k].h.id == b[k].h.id && a[k].h.t == b[k].h.t && a[k].h.u == b[k].h.u &&
                                           a[k].h.v == b[k].h.v));
        mismatches += !same;
    }
    CHECK(mismatches == 0);
    CHECK(s1.passes == s2.passes);
    CHECK(s1.rays == s2.rays);
    CHECK(s1.hits == s2.hits);
    CHECK(s1.tests <= s1.rays * mesh.size());
    for (const auto& c : w1.cones) {
        REQUIRE(all_finite(c.apex));
        REQUIRE(std::isfinite(c.cos_half));
    }
    return s1;
}

template <class T>
std::vector<Ray<T>> camera(const Mesh<T>& mesh, int w, int h) {
    return make_primary_rays<T>(std::span<const TriangleVertices<T>>(mesh), w, h);
}

}  // namespace

TEST_CASE("agreement: glass passes of the ray-tile engine are identical to brute force") {
    const Mesh<float> knot = make_torus_knot<float>(60, 10);  // 1200 triangles
    const int n = image_size;
    for (int tile : {8, 16})
        for (bool split : {false, true}) {
            CAPTURE(tile);
            CAPTURE(split);
            const TileOptions opt = split ? TileOptions{} : TileOptions::fixed();
            const PassStats s = compare_passes<Ivm<float>>(knot, camera(knot, n, n), TileGrid(n, n, tile), 5, opt);
            MESSAGE("tile " << tile << (split ? " split" : " fixed") << ": " << s.passes << " passes, " << s.rays
                            << " rays, tests per ray " << s.tests_per_ray() << " of " << knot.size()
                            << ", fallback cones " << s.tiles_all << "/" << s.tiles);
            CHECK(s.passes >= 3);
            CHECK(s.tests_per_ray() < 0.5 * double(knot.size()));  // the cones cull
        }
    // 000's interleaved order, double precision, another intersector, a partial last tile.
    TileOptions interleaved = TileOptions::fixed();
    interleaved.cone.order = ConeOrder::interleaved;
    compare_passes<Ivm<float>>(knot, camera(knot, n, n), TileGrid(n, n, 16), 4, interleaved);
    const Mesh<double> knot_d = make_torus_knot<double>(40, 8);
    compare_passes<Ivm<double>>(knot_d, camera(knot_d, 37, 29), TileGrid(37, 29, 8), 5);
    compare_passes<MollerTrumbore<float>>(knot, camera(knot, 37, 29), TileGrid(37, 29, 16), 5);
    // A sphere (with its degenerate pole triangles) far from the origin.
    const Mesh<float> far_sphere = make_sphere<float>(20, 30, Vec3f(1e3f, -2e3f, 5e2f), 2.0f);
    compare_passes<Ivm<float>>(far_sphere, camera(far_sphere, n, n), TileGrid(n, n, 8), 5);
}

TEST_CASE("stress: incoherent, parallel, identical and broken rays in the engine match brute force") {
    const Mesh<float> soup = make_soup<float>(600, 3);
    const std::span<const TriangleVertices<float>> tris(soup);
    const int w = 32, h = 32;
    // Incoherent: diffuse rays leaving the triangles (every cone falls back).
    auto inc = make_incoherent_rays<float>(tris, std::size_t(w) * h);
    inc.resize(std::size_t(w) * h);
    const PassStats si = compare_passes<Ivm<float>>(soup, inc, TileGrid(w, h, 8), 3);
    CHECK(si.tiles_all > 0);
    // Parallel (orthographic) rays and identical rays per tile, plus NaN, infinite, zero and
    // tiny directions scattered in.
    std::vector<Ray<float>> rays(std::size_t(w) * h);
    Pcg32 rng(41);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            Ray<float>& r = rays[std::size_t(y) * w + x];
            if (y < h / 2) {
                r.origin = Vec3f(float(x) / w, float(y) / h * 2, -1.0f);
                r.direction = Vec3f(0, 0, 1);
            } else {
                r.origin = Vec3f(0.5f, 0.5f, 2.0f);
                r.direction = Vec3f(float(x / 8) * 0.1f - 0.15f, float(y / 8) * 0.1f - 0.3f, -1.0f);
            }
            switch (rng.bounded(40)) {
                case 0: r.origin.x = std::nanf(""); break;
                case 1: r.direction = Vec3f(0); break;
                case 2: r.direction.y = infinity<float>; break;
                case 3: r.direction *= 1e-30f; break;
                case 4: r.direction = -r.direction; break;  // nearly opposite within a tile
                default: break;
            }
        }
    compare_passes<Ivm<float>>(soup, rays, TileGrid(w, h, 8), 4);
    TileOptions interleaved;
    interleaved.cone.order = ConeOrder::interleaved;
    compare_passes<Ivm<float>>(soup, rays, TileGrid(w, h, 16), 4, interleaved);
    compare_passes<Ivm<float>>(soup, rays, TileGrid(w, h, 16), 4, TileOptions::fixed());
    // Degenerate and non-finite triangles in the mesh.
    Mesh<float> bad = soup;
    bad[3] = {Vec3f(0.5f), Vec3f(0.5f), Vec3f(0.6f)};
    bad[7] = {Vec3f(0.2f), Vec3f(std::nanf(""), 0, 0), Vec3f(0.3f)};
    bad[9] = {Vec3f(0.1f, 0.1f, 0.1f), Vec3f(0.2f, 0.2f, 0.2f), Vec3f(0.3f, 0.3f, 0.3f)};
    compare_passes<Ivm<float>>(bad, rays, TileGrid(w, h, 8), 3);
}

namespace {

/// The record of `tri` in the frame at the stored `origin`, built here (the origin is only
/// widened from T: there is no rounding for a compiler to fold away).
template <class P>
[[gnu::noinline]] P record_in_frame(const TriangleVertices<typename P::scalar_type>& tri,
                                    const Vec3<typename P::scalar_type>& origin) {
    const Vec3d o(origin);
    return P::build(Vec3d(tri[0]) - o, Vec3d(tri[1]) - o, Vec3d(tri[2]) - o);
}

/// Records of `store` that differ from the record of their triangle built in their group's
/// stored frame.
template <class P>
std::size_t records_off_frame(const TriangleStore<P>& store, std::span<const TriangleVertices<typename P::scalar_type>> tris) {
    std::size_t off = 0;
    for (std::size_t gi = 0; gi < store.group_count(); ++gi) {
        const auto& g = store.group(gi);
        for (std::uint32_t r = g.begin; r < g.end; ++r) {
            const P have = store.record(r), want = record_in_frame<P>(tris[store.id(r)], g.origin);
            off += std::memcmp(&have, &want, sizeof(P)) != 0;
        }
    }
    return off;
}

}  // namespace

// The frame origin is chosen in double and rounded to T, and a record is built from the
// vertices minus that rounded origin. GCC 12.2 (-O2, -O3) folded the round trip double -> T
// -> double into the identity where its SLP vectorizer packed x and y: the records were built
// in a frame off the stored one by the rounding, and whether a copy of the build had the error
// depended on inlining, so brute force and the engine built in one program could disagree in
// the last bits of their hits (detail::rounded_to keeps the rounding).
TEST_CASE("exact: every store builds its records in the frame it stores (brute force, the engine, blocks)") {
    const Mesh<float> sphere = make_sphere<float>(5, 10), knot = make_torus_knot<float>(31, 16);
    const Mesh<double> knot_d = make_torus_knot<double>(20, 8);
    for (const Mesh<float>* m : {&sphere, &knot}) {
        const std::span<const TriangleVertices<float>> tris(*m);
        CAPTURE(tris.size());
        const BruteForce<Ivm<float>> brute(tris);
        const RayTileEngine<Ivm<float>> engine(tris, TileOptions::fixed());
        CHECK(records_off_frame(brute.store(), tris) == 0);
        CHECK(records_off_frame(engine.store(), tris) == 0);
        TriangleStore<Ivm<float>> blocks;  // groups of many triangles, padded and not
        std::vector<std::uint32_t> ids(tris.size());
        for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = std::uint32_t(i);
        const std::size_t half = tris.size() / 2;
        blocks.add_block(tris.first(half), std::span<const std::uint32_t>(ids).first(half));
        blocks.add_block(tris.subspan(half), std::span<const std::uint32_t>(ids).subspan(half),
                         TriangleStore<Ivm<float>>::Padding::batches);
        CHECK(records_off_frame(blocks, tris) == 0);
        // And so the two stores hold the same bits, record for record.
        for (std::size_t i = 0; i < tris.size(); ++i) {
            const Ivm<float> a = brute.store().record(brute.store().group(i).begin);
            const Ivm<float> b = engine.store().record(engine.store().group(i).begin);
            CHECK(std::memcmp(&a, &b, sizeof a) == 0);
        }
    }
    const std::span<const TriangleVertices<double>> tris_d(knot_d);
    CHECK(records_off_frame(BruteForce<Ivm<double>>(tris_d).store(), tris_d) == 0);
}

TEST_CASE("stress: bad input throws glint::Error") {
    CHECK_THROWS_AS(TileGrid(0, 4, 8), Error);
    CHECK_THROWS_AS(TileGrid(4, 4, 0), Error);
    TileOptions bad;
    bad.min_tile = 0;
    CHECK_THROWS_AS(RayTileEngine<Ivm<float>>(std::span<const TriangleVertices<float>>(), bad), Error);
    const Mesh<float> soup = make_soup<float>(10, 3);
    const RayTileEngine<Ivm<float>> engine{std::span<const TriangleVertices<float>>(soup)};
    std::vector<Ray<float>> rays(10);
    std::vector<std::uint8_t> active(10, 1);
    std::vector<StoreHit<float>> hits(10);
    TileWorkspace<float> ws;
    CHECK_THROWS_AS(engine.trace(rays, active, TileGrid(4, 4, 2), hits, ws), Error);
    auto stop = [](std::size_t, Ray<float>&, const StoreHit<float>&, bool) { return false; };
    CHECK_THROWS_AS(engine.trace_passes(std::span<Ray<float>>(rays), TileGrid(5, 2, 2), -1, stop, ws), Error);
    const PassStats none = engine.trace_passes(std::span<Ray<float>>(rays), TileGrid(5, 2, 2), 0, stop, ws);
    CHECK(none.passes == 0);
}
