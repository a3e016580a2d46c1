// Tests for glint/occluders: exact predicates, Delaunay tetrahedralization, occluder-sphere
// generation and merging (GSSA), occluder visibility, and the VPL renderer.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include <glint/core/random.hpp>
#include <glint/occluders/delaunay.hpp>
#include <glint/occluders/predicates.hpp>

using namespace glint;

namespace {

Vec3d rand_point(Pcg32& rng) { return {rng.uniform<double>(), rng.uniform<double>(), rng.uniform<double>()}; }

/// Full structural and Delaunay check of a tessellation with exact predicates: every
/// tetrahedron positively oriented, adjacency symmetric over shared faces, every face
/// locally Delaunay (the opposite vertex across it not strictly inside the circumsphere;
/// local implies global for a triangulation of a convex region), volumes summing to the
/// enclosing tetrahedron's and every distinct input point used.
template <class T>
void check_delaunay(const Delaunay<T>& d, std::size_t distinct_points) {
    const auto tets = d.all_tetrahedra();
    const auto& p = d.points();
    std::map<std::array<std::int32_t, 3>, std::vector<std::pair<std::size_t, int>>> faces;
    double volume = 0;
    std::set<std::int32_t> used;
    std::size_t bad_orient = 0, bad_local = 0, bad_faces = 0;
    for (std::size_t t = 0; t < tets.size(); ++t) {
        const auto& v = tets[t].v;
        if (orient3d(p[v[0]], p[v[1]], p[v[2]], p[v[3]]) <= 0) ++bad_orient;
        volume += glm::dot(p[v[1]] - p[v[0]], glm::cross(p[v[2]] - p[v[0]], p[v[3]] - p[v[0]])) / 6.0;
        for (int i = 0; i < 4; ++i) {
            used.insert(v[i]);
            std::array<std::int32_t, 3> f;
            int k = 0;
            for (int j = 0; j < 4; ++j)
                if (j != i) f[k++] = v[j];
            std::sort(f.begin(), f.end());
            faces[f].push_back({t, i});
        }
    }
    for (const auto& [f, owners] : faces) {
        if (owners.size() == 1) continue;  // hull of the enclosing tetrahedron
        if (owners.size() != 2) {
            ++bad_faces;
            continue;
        }
        for (int s = 0; s < 2; ++s) {
            const auto& a = tets[owners[s].first].v;
            const auto& b = tets[owners[1 - s].first].v;
            const Vec3d e = p[b[owners[1 - s].second]];
            if (insphere(p[a[0]], p[a[1]], p[a[2]], p[a[3]], e) > 0) ++bad_local;
        }
    }
    CHECK(bad_orient == 0);
    CHECK(bad_faces == 0);
    CHECK(bad_local == 0);
    const auto& s = p;
    const double super = glm::dot(s[1] - s[0], glm::cross(s[2] - s[0], s[3] - s[0])) / 6.0;
    CHECK(std::abs(volume - std::abs(super)) <= 1e-9 * std::abs(super));
    CHECK(used.size() == distinct_points + 4);
}

/// Brute force: no input point strictly inside any reported tetrahedron's circumsphere.
template <class T>
void check_empty_brute(const Delaunay<T>& d) {
    const auto& p = d.points();
    std::size_t bad = 0;
    for (const auto& t : d.all_tetrahedra())
        for (std::size_t i = 4; i < p.size(); ++i)
            if (insphere(p[t.v[0]], p[t.v[1]], p[t.v[2]], p[t.v[3]], p[i]) > 0) ++bad;
    CHECK(bad == 0);
}

/// Integer points on the sphere x^2 + y^2 + z^2 = n2 (exactly cospherical).
std::vector<Vec3d> integer_sphere_points(int n2) {
    std::vector<Vec3d> out;
    const int r = int(std::sqrt(double(n2))) + 1;
    for (int x = -r; x <= r; ++x)
        for (int y = -r; y <= r; ++y) {
            const int z2 = n2 - x * x - y * y;
            if (z2 < 0) continue;
            const int z = int(std::lround(std::sqrt(double(z2))));
            if (z * z != z2) continue;
            out.push_back(Vec3d(x, y, z));
            if (z != 0) out.push_back(Vec3d(x, y, -z));
        }
    return out;
}

}  // namespace

TEST_CASE("predicates: exact signs on simple and degenerate configurations") {
    const Vec3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0, 0, 1);
    CHECK(orient3d(a, b, c, d) == 1);
    CHECK(orient3d(a, c, b, d) == -1);
    CHECK(orient3d(a, b, c, Vec3d(0.3, 0.2, 0)) == 0);
    CHECK(insphere(a, b, c, d, Vec3d(0.25, 0.25, 0.25)) == 1);
    CHECK(insphere(a, b, c, d, Vec3d(2, 2, 2)) == -1);
    CHECK(insphere(a, b, c, d, Vec3d(1, 1, 0)) == 0);  // the circumsphere passes through (1,1,0)
    // Nearly degenerate: coplanar points far from the origin, perturbed by one ulp.
    const double big = 1e8;
    const Vec3d A(big, big, big), B(big + 1, big, big), C(big, big + 1, big);
    CHECK(orient3d(A, B, C, Vec3d(big + 0.5, big + 0.5, big)) == 0);
    CHECK(orient3d(A, B, C, Vec3d(big + 0.5, big + 0.5, std::nextafter(big, 2 * big))) == 1);
    CHECK(orient3d(A, B, C, Vec3d(big + 0.5, big + 0.5, std::nextafter(big, 0.0))) == -1);
}

TEST_CASE("predicates: exact path agrees with the filter on random input") {
    Pcg32 rng(5);
    int disagreements = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3d a = rand_point(rng), b = rand_point(rng), c = rand_point(rng), d = rand_point(rng),
                    e = rand_point(rng);
        const double o = detail::orient3d_exact(a, b, c, d);
        disagreements += (o > 0 ? 1 : (o < 0 ? -1 : 0)) != orient3d(a, b, c, d);
        const double s = detail::insphere_exact(a, b, c, d, e);
        const int so = orient3d(a, b, c, d);
        disagreements += (s > 0 ? 1 : (s < 0 ? -1 : 0)) != insphere(a, b, c, d, e);
        // insphere is positive inside for positive orientation: swap two vertices flips it.
        if (so != 0) disagreements += insphere(a, b, c, d, e) != -insphere(b, a, c, d, e);
    }
    CHECK(disagreements == 0);
    // Cospherical integer points: insphere is exactly 0 for every quintuple.
    const auto s = integer_sphere_points(50 * 50);
    int nonzero = 0, tried = 0;
    for (std::size_t i = 0; i + 4 < s.size() && tried < 2000; i += 1, ++tried) {
        const Vec3d &p0 = s[i], &p1 = s[(i * 7 + 1) % s.size()], &p2 = s[(i * 13 + 2) % s.size()],
                    &p3 = s[(i * 29 + 3) % s.size()], &p4 = s[(i * 31 + 4) % s.size()];
        if (orient3d(p0, p1, p2, p3) == 0) continue;
        nonzero += insphere(p0, p1, p2, p3, p4) != 0;
    }
    CHECK(nonzero == 0);
}

TEST_CASE("delaunay: small random set, brute-force empty circumspheres") {
    Pcg32 rng(1);
    std::vector<Vec3d> pts(300);
    for (auto& q : pts) q = rand_point(rng);
    Delaunay<double> d(pts);
    check_delaunay(d, pts.size());
    check_empty_brute(d);
}

TEST_CASE("delaunay: random, gridded, coplanar, cospherical and duplicate sets") {
#ifdef GLINT_LONG_TESTS
    const std::size_t n_random = 100000;
    const int grid = 46;  // 97336 points
#else
    const std::size_t n_random = 10000;
    const int grid = 21;  // 9261 points
#endif
    SUBCASE("random") {
        Pcg32 rng(2);
        std::vector<Vec3d> pts(n_random);
        for (auto& q : pts) q = rand_point(rng);
        Delaunay<double> d(pts);
        check_delaunay(d, pts.size());
        MESSAGE(n_random << " random points: " << d.build_seconds() << " s");
    }
    SUBCASE("grid") {
        std::vector<Vec3d> pts;
        for (int x = 0; x < grid; ++x)
            for (int y = 0; y < grid; ++y)
                for (int z = 0; z < grid; ++z) pts.push_back(Vec3d(x, y, z) * 0.1);
        Delaunay<double> d(pts);
        check_delaunay(d, pts.size());
        MESSAGE(pts.size() << " gridded points: " << d.build_seconds() << " s");
    }
    SUBCASE("cospherical") {
        auto pts = integer_sphere_points(125 * 125);  // exactly cospherical
        const std::size_t n = pts.size();
        Delaunay<double> d(pts);
        check_delaunay(d, n);
        MESSAGE(n << " cospherical points: " << d.build_seconds() << " s");
    }
    SUBCASE("coplanar layers, float input, duplicates") {
        std::vector<Vec3f> pts;
        Pcg32 rng(3);
        for (int i = 0; i < 2000; ++i)
            pts.push_back(Vec3f(rng.uniform<float>(), rng.uniform<float>(), float(i % 3)));
        const std::size_t distinct = pts.size();
        for (int i = 0; i < 100; ++i) pts.push_back(pts[std::size_t(i * 7)]);
        Delaunay<float> d(pts);
        CHECK(d.duplicate_count() == 100);
        check_delaunay(d, distinct);
    }
}

TEST_CASE("delaunay: stress - far from the origin, tiny extent, bad input") {
    Pcg32 rng(4);
    std::vector<Vec3d> pts(2000);
    for (auto& q : pts) q = Vec3d(1e6) + 1e-3 * rand_point(rng);
    Delaunay<double> d(pts);
    check_delaunay(d, pts.size());
    const std::vector<Vec3d> nan_input = {Vec3d(0), Vec3d(NAN, 0, 0)};
    CHECK_THROWS_AS(Delaunay<double>{nan_input}, glint::Error);
    Delaunay<double> empty(std::vector<Vec3d>{});
    CHECK(empty.tetrahedra().empty());
}
