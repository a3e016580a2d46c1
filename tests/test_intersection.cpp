// Tests for glint/intersection: exact hits, agreement with the extended-precision reference
// on 10^6 random pairs per policy, and stress cases (closed-mesh edges and vertices,
// slivers, zero area, parallel rays, far coordinates, planes through the origin, NaN/inf).
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>
#include <string_view>

#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/wald.hpp>
#include <glint/intersection/watertight.hpp>

#include <glint/trees/brute_force.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "../benchmarks/support/intersector_names.hpp"
#include "intersection_cases.hpp"

using namespace glint;
using namespace glint::testing;
using glint::bench::intersector_name;

#define GLINT_ALL_POLICIES                                                                 \
    Ivm<float>, MollerTrumbore<float>, Wald<float>, Watertight<float>, Ivm<double>,        \
        MollerTrumbore<double>, Wald<double>, Watertight<double>

static_assert(TriangleIntersector<Ivm<float>> && TriangleIntersector<Wald<double>>);
static_assert(sizeof(Ivm<float>) == 9 * sizeof(float), "the IVM record is exactly 9 scalars");
static_assert(sizeof(MollerTrumbore<float>) == 9 * sizeof(float));
static_assert(sizeof(Watertight<float>) == 9 * sizeof(float));

// Decisions may differ from the reference only within this many "edge ulps" (see
// reference.hpp). A few ulps of the coordinates' magnitude is what a correct test in
// precision T can be off by; the agreement cases print the widest band they saw.
constexpr double kBand = 16.0;

TEST_CASE_TEMPLATE("exact: known hits, barycentrics and misses", P, GLINT_ALL_POLICIES) {
    using T = typename P::scalar_type;
    const Vec3<T> v0(1, 1, 4), v1(5, 1, 4), v2(1, 5, 4);
    const Triangle<P> tri(v0, v1, v2);
    TriangleHit<T> h;

    // Hit at (2, 3, 4) from (2, 3, 0): t = 4 for d = (0,0,1), 2 for d = (0,0,2);
    // barycentrics u = (x - 1)/4 = 1/4, v = (y - 1)/4 = 1/2.
    REQUIRE(tri.intersect(Ray<T>{{2, 3, 0}, {0, 0, 1}}, h));
    CHECK(h.t == doctest::Approx(4).epsilon(1e-6));
    CHECK(h.u == doctest::Approx(0.25).epsilon(1e-6));
    CHECK(h.v == doctest::Approx(0.5).epsilon(1e-6));
    REQUIRE(tri.intersect(Ray<T>{{2, 3, 0}, {0, 0, 2}}, h));
    CHECK(h.t == doctest::Approx(2).epsilon(1e-6));
    // From the other side (back face): still a hit, no culling.
    REQUIRE(tri.intersect(Ray<T>{{2, 3, 9}, {0, 0, -1}}, h));
    CHECK(h.t == doctest::Approx(5).epsilon(1e-6));
    // Oblique: from (0, 0, 0) towards the centroid (7/3, 7/3, 4): t = 1, u = v = 1/3.
    REQUIRE(tri.intersect(Ray<T>{{0, 0, 0}, {T(7) / 3, T(7) / 3, 4}}, h));
    CHECK(h.t == doctest::Approx(1).epsilon(1e-5));
    CHECK(h.u == doctest::Approx(1.0 / 3).epsilon(1e-5));
    CHECK(h.v == doctest::Approx(1.0 / 3).epsilon(1e-5));

    // Misses: outside each edge, behind the origin, beyond tmax, before tmin.
    CHECK_FALSE(tri.intersect(Ray<T>{{4, 4, 0}, {0, 0, 1}}, h));   // past the hypotenuse
    CHECK_FALSE(tri.intersect(Ray<T>{{0.5, 3, 0}, {0, 0, 1}}, h)); // left of v0-v2
    CHECK_FALSE(tri.intersect(Ray<T>{{3, 0.5, 0}, {0, 0, 1}}, h)); // below v0-v1
    CHECK_FALSE(tri.intersect(Ray<T>{{2, 3, 0}, {0, 0, -1}}, h));  // pointing away
    CHECK_FALSE(tri.intersect(Ray<T>{{2, 3, 0}, {0, 0, 1}, 0, 3.5}, h));
    CHECK_FALSE(tri.intersect(Ray<T>{{2, 3, 0}, {0, 0, 1}, 4.5, 10}, h));
}

TEST_CASE_TEMPLATE("agreement: batch kernel equals the scalar test", P, GLINT_ALL_POLICIES) {
    using T = typename P::scalar_type;
    const auto cases = random_cases<T>(101, 20000);
    // One block of 64 random triangles; many rays; the store's closest hit must be the
    // minimum over the scalar tests (same record values, same frame).
    std::vector<TriangleVertices<T>> tris;
    std::vector<std::uint32_t> ids;
    for (std::uint32_t i = 0; i < 64; ++i) {
        tris.push_back(cases[i].tri);
        ids.push_back(i);
    }
    TriangleStore<P> store;
    const auto block = store.add_block(tris, ids);
    std::size_t hits = 0, mismatches = 0;
    for (const auto& c : cases) {
        StoreHit<T> batch_hit;
        const bool b = store.closest_hit(block, c.ray, batch_hit);
        // Scalar reference over the same records.
        T best = infinity<T>;
        std::uint32_t best_id = ~0u;
        for (std::size_t g = 0; g < store.group_count(); ++g) {
            const auto& grp = store.group(g);
            const auto rd = P::prepare(TriangleStore<P>::Frame::local(c.ray, grp.origin));
            for (std::uint32_t i = grp.begin; i < grp.end; ++i) {
                TriangleHit<T> h;
                if (intersect_record(store.record(i), rd, h) && h.t < best) {
                    best = h.t;
                    best_id = store.id(i);
                }
            }
        }
        hits += b;
        if (b != (best_id != ~0u) || (b && (batch_hit.id != best_id))) ++mismatches;
        CHECK(store.any_hit(block, c.ray) == b);
    }
    INFO(intersector_name<P>, " hits ", hits, " mismatches ", mismatches);
    CHECK(hits > 1000);
    // Vectorized and scalar code may round differently (FMA contraction); allow only
    // a handful of edge cases out of 20000.
    CHECK(mismatches <= 4);
}

template <class P>
void check_agreement(const char* what, const Agreement& a, std::size_t expected_pairs) {
    std::printf("  %-10s %-16s %-6s pairs %zu  ref hits %zu  disagreements %zu (miss %zu, hit %zu)  "
                "widest %.2g ulps  max t err %.2g ulps\n",
                what, intersector_name<P>, sizeof(typename P::scalar_type) == 4 ? "float" : "double", a.pairs,
                a.reference_hits, a.false_miss + a.false_hit, a.false_miss, a.false_hit,
                a.max_disagreement_ulps, a.max_t_ulps);
    CHECK(a.pairs == expected_pairs);
    CHECK(a.undefined < a.pairs / 1000);
    CHECK(a.reference_hits > a.pairs / 8);  // the mix really has hits and misses (about 22%)
    CHECK(a.reference_hits < a.pairs / 2);
    CHECK(a.max_t_ulps < kBand);            // t within a few ulps of the plane's position
    CHECK(a.false_miss_far == 0);
    CHECK(a.false_hit_far == 0);
    CHECK_FALSE(a.nan_out);
}

TEST_CASE_TEMPLATE("agreement: 10^6 random pairs against the extended-precision reference", P,
                   GLINT_ALL_POLICIES) {
    using T = typename P::scalar_type;
    const std::size_t n = 1'000'000;
    const Agreement a = measure_agreement<P>(random_cases<T>(2024, n), kBand);
    check_agreement<P>("random", a, n);
}

TEST_CASE_TEMPLATE("stress: slivers agree with the reference outside the edge band", P,
                   GLINT_ALL_POLICIES) {
    using T = typename P::scalar_type;
    const std::size_t n = 100'000;
    check_agreement<P>("sliver", measure_agreement<P>(sliver_cases<T>(7, n), kBand), n);
}

TEST_CASE_TEMPLATE("stress: coordinates 10^3 to 10^6 from the origin", P, GLINT_ALL_POLICIES) {
    using T = typename P::scalar_type;
    for (T offset : {T(1e3), T(1e4), T(1e5), T(1e6)}) {
        const std::size_t n = 50'000;
        CAPTURE(offset);
        check_agreement<P>("far", measure_agreement<P>(random_cases<T>(99, n, offset), kBand), n);
    }
}

TEST_CASE_TEMPLATE("stress: triangle planes through the origin", P, GLINT_ALL_POLICIES) {
    using T = typename P::scalar_type;
    const std::size_t n = 100'000;
    check_agreement<P>("origin", measure_agreement<P>(origin_plane_cases<T>(5, n), kBand), n);
    // Exact case: the plane z = 0 through the origin, hit straight on.
    TriangleHit<T> h;
    const Triangle<P> tri(Vec3<T>(-1, -1, 0), Vec3<T>(1, -1, 0), Vec3<T>(0, 1, 0));
    REQUIRE(tri.intersect(Ray<T>{{0, 0, -2}, {0, 0, 1}}, h));
    CHECK(h.t == doctest::Approx(2).epsilon(1e-6));
    CHECK(h.u == doctest::Approx(0.25).epsilon(1e-6));
    CHECK(h.v == doctest::Approx(0.5).epsilon(1e-6));
}

TEST_CASE_TEMPLATE("stress: zero-area triangles, parallel rays, NaN and infinity all miss", P,
                   GLINT_ALL_POLICIES) {
    using T = typename P::scalar_type;
    for (const auto& entry : {std::pair{"zero-area", zero_area_cases<T>(13, 30000)},
                              std::pair{"parallel", parallel_cases<T>(17, 10000)},
                              std::pair{"nonfinite", nonfinite_cases<T>()}}) {
        const char* what = entry.first;  // not a structured binding: clang 14 cannot capture one
        const auto& cases = entry.second;
        CAPTURE(what);
        const Agreement a = measure_agreement<P>(cases, kBand);
        CHECK(a.reference_hits == 0);  // the reference agrees that none is a hit
        // Zero area and parallel rays are undefined for the reference, so that any hit by the
        // policy counts as a far false hit (the non-finite cases are defined misses).
        if (std::string_view(what) != "nonfinite") CHECK(a.undefined == a.pairs);
        CHECK(a.false_hit == 0);
        CHECK_FALSE(a.nan_out);
    }
    // The store's batch kernel too: no hit, and the hit record left untouched.
    for (const auto& c : nonfinite_cases<T>()) {
        TriangleStore<P> store;
        const std::uint32_t id = 0;
        const auto block = store.add_block(std::span(&c.tri, 1), std::span(&id, 1));
        StoreHit<T> sh;
        CHECK_FALSE(store.closest_hit(block, c.ray, sh));
        CHECK(std::isinf(sh.t));
    }
}

TEST_CASE_TEMPLATE("stress: rays through shared edges and vertices of a closed mesh", P,
                   GLINT_ALL_POLICIES) {
    using T = typename P::scalar_type;
    std::size_t total = 0;
    const std::size_t total_leaks = closed_mesh_leaks<P>(total);
    std::printf("  closed-mesh %-16s %-6s rays %zu leaks %zu (%.3g%%)\n", intersector_name<P>,
                sizeof(T) == 4 ? "float" : "double", total, total_leaks,
                100.0 * double(total_leaks) / double(total));
    CHECK(total > 20000);
    if constexpr (std::is_same_v<P, Watertight<T>>) {
        CHECK(total_leaks == 0);  // the watertight test never lets a ray through
    }
}

namespace {
/// OffsetFrames::choose for one triangle, out of line as the store's builder may call it.
[[gnu::noinline]] Vec3d frame_origin(const TriangleVertices<float>& tri) {
    double q = 0;
    return OffsetFrames::choose<float>(std::span(&tri, 1), q);
}
}  // namespace

TEST_CASE("IVM frames: origins are exact floats (the frame rays are translated by)") {
    // Rays are translated by a group's float origin, so the record must be built in exactly
    // that frame: choose() returns it rounded. GCC 12 once vectorized the rounding away in
    // two of three components where choose was inlined (test_cones checks the stores' records).
    const auto mesh = icosphere<float>(3, Vec3f(0.3f, -1.7f, 2.9f), 0.77f);
    int inexact = 0;
    for (const auto& tri : mesh.triangles()) {
        const Vec3d o = frame_origin(tri);
        // A double is a float's value when the 29 low bits of its 52-bit mantissa are zero.
        for (int k = 0; k < 3; ++k) inexact += (std::bit_cast<std::uint64_t>(o[k]) & ((std::uint64_t(1) << 29) - 1)) != 0;
    }
    CHECK(inexact == 0);
}

TEST_CASE("IVM frames: blocks get well-conditioned frames, split only when needed") {
    // A leaf of 8 triangles of a closed mesh: one frame suffices.
    const auto mesh = icosphere<float>(2, Vec3f(5, 5, 5), 1.0f);
    auto tris = mesh.triangles();
    std::vector<TriangleVertices<float>> leaf(tris.begin(), tris.begin() + 8);
    double quality = 0;
    detail::choose_frame<float>(leaf, quality);
    CHECK(quality >= detail::min_frame_quality);
    {
        // ... and so the leaf, added as one block, stays one group.
        TriangleStore<Ivm<float>> one;
        std::vector<std::uint32_t> leaf_ids(leaf.size());
        for (std::size_t i = 0; i < leaf_ids.size(); ++i) leaf_ids[i] = static_cast<std::uint32_t>(i);
        one.add_block(leaf, leaf_ids);
        CHECK(one.group_count() == 1);
    }
    // A whole closed sphere in one block: no single point is far from all its planes, so
    // the block is split into groups; every record then has quality >= 1/8.
    TriangleStore<Ivm<float>> store;
    std::vector<std::uint32_t> ids(tris.size());
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::uint32_t>(i);
    store.add_block(tris, ids);
    CHECK(store.size() == tris.size());
    CHECK(store.group_count() > 1);
    for (std::size_t g = 0; g < store.group_count(); ++g) {
        const auto& grp = store.group(g);
        for (std::uint32_t i = grp.begin; i < grp.end; ++i) {
            const std::uint32_t id = store.id(i);
            const Vec3d o(grp.origin);
            CHECK(detail::frame_quality(o, Vec3d(tris[id][0]), Vec3d(tris[id][1]), Vec3d(tris[id][2])) >=
                  detail::min_frame_quality);
        }
    }
    // Bad input is reported, not ignored.
    CHECK_THROWS_AS(store.add_block(tris, std::span<const std::uint32_t>(ids).first(3)), Error);
}

namespace {
/// A user's intersector with only what the concept asks for: the scalar type, build,
/// prepare and test. No name, no frame, no batch kernel, no load or store: the containers
/// derive them. It restates Möller-Trumbore's arithmetic operation for operation, so that
/// every hit must equal MollerTrumbore<float>'s bit for bit, ties at shared edges included.
struct UserTriangle {
    using scalar_type = float;
    Vec3f v0, e1, e2;

    struct Shot {
        Vec3f o, d;
        float tmin, tmax;
    };
    static UserTriangle build(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
        if (detail::degenerate_triangle(a, b, c)) return {Vec3f(a), Vec3f(0), Vec3f(0)};
        return {Vec3f(a), Vec3f(b - a), Vec3f(c - a)};
    }
    static Shot prepare(const Ray<float>& r) { return {r.origin, r.direction, r.tmin, r.tmax}; }
    bool test(const Shot& r, float& t, float& u, float& v) const {
        const float px = r.d.y * e2.z - r.d.z * e2.y, py = r.d.z * e2.x - r.d.x * e2.z,
                    pz = r.d.x * e2.y - r.d.y * e2.x;
        const float det = e1.x * px + e1.y * py + e1.z * pz, inv = 1.0f / det;
        const float sx = r.o.x - v0.x, sy = r.o.y - v0.y, sz = r.o.z - v0.z;
        u = (sx * px + sy * py + sz * pz) * inv;
        const float qx = sy * e1.z - sz * e1.y, qy = sz * e1.x - sx * e1.z, qz = sx * e1.y - sy * e1.x;
        v = (r.d.x * qx + r.d.y * qy + r.d.z * qz) * inv;
        t = (e2.x * qx + e2.y * qy + e2.z * qz) * inv;
        return (det != 0.0f) & (u >= 0.0f) & (v >= 0.0f) & (u + v <= 1.0f) & (t > r.tmin) & (t < r.tmax);
    }
};
static_assert(TriangleIntersector<UserTriangle>);
static_assert(field_count<UserTriangle> == 9);

/// Rays on which two accelerators differ: in hit or miss, any hit, the triangle, t, u or v.
template <class A, class B>
std::size_t count_disagreements(const A& a, const B& b, const std::vector<Ray<float>>& rays, std::size_t& hits) {
    std::size_t bad = 0;
    hits = 0;
    for (const auto& r : rays) {
        StoreHit<float> ha, hb;
        const bool x = a.closest_hit(r, ha), y = b.closest_hit(r, hb);
        hits += x;
        bad += x != y || ha.id != hb.id || ha.t != hb.t || ha.u != hb.u || ha.v != hb.v || a.any_hit(r) != b.any_hit(r);
    }
    return bad;
}
}  // namespace

TEST_CASE("a user's intersector with only build, prepare and test plugs into every container") {
    // A closed sphere and an offset one (the rays cross both); rays at the first one's
    // edges and vertices, and random rays at random triangles.
    const auto sphere = icosphere<float>(3, Vec3f(0.2f, -0.1f, 0.3f), 1.0f);
    auto tris = sphere.triangles();
    const auto other = icosphere<float>(2, Vec3f(1.5f, 0.5f, -0.5f), 0.7f).triangles();
    tris.insert(tris.end(), other.begin(), other.end());
    std::vector<Ray<float>> rays = edge_vertex_rays(sphere, 3, 4);
    const auto cases = random_cases<float>(11, 20000);
    for (const auto& c : cases) rays.push_back(c.ray);

    // Triangle: the scalar path.
    std::size_t single_bad = 0;
    for (const auto& c : cases) {
        TriangleHit<float> hu, hm;
        const bool x = Triangle<UserTriangle>(c.tri[0], c.tri[1], c.tri[2]).intersect(c.ray, hu);
        const bool y = Triangle<MollerTrumbore<float>>(c.tri[0], c.tri[1], c.tri[2]).intersect(c.ray, hm);
        single_bad += x != y || hu.t != hm.t || hu.u != hm.u || hu.v != hm.v;
    }
    CHECK(single_bad == 0);

    // A TriangleStore under brute force (the batch path with blocks cut mid-batch), and a
    // wide BVH over TriangleLeaves (padded leaves, full batches).
    std::size_t hits = 0;
    CHECK(count_disagreements(BruteForce<UserTriangle>(tris), BruteForce<MollerTrumbore<float>>(tris), rays, hits) ==
          0);
    CHECK(hits > rays.size() / 4);
    const MeshBvh<UserTriangle> user_bvh(tris);
    CHECK(count_disagreements(user_bvh, MeshBvh<MollerTrumbore<float>>(tris), rays, hits) == 0);
    CHECK(hits > rays.size() / 4);
    CHECK(user_bvh.leaves().store().size() % batch_width == 0);  // padded leaves
}
