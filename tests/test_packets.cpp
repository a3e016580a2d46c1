// Tests of MeshBvh's ray streams (closest_hit / any_hit over spans of rays, traversed in
// packets of 8 and 16 where the rays are coherent): every ray's answer is the single-ray query's,
// bit for bit (t, u, v, triangle id; occluded or not), with every kernel the CPU runs.
//
// Rays per scene and kind: GLINT_PACKET_RAYS from the environment, default 2^14 (CI; 2^11
// under the sanitizers, -DGLINT_SANITIZER_TESTS); GLINT_PACKET_RAYS=1000000 runs the 10^6
// rays per scene of the Release check (docs/notes/packets.md gives its time).
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/random.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/watertight.hpp>
#include <glint/trees/brute_force.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "support/tree_scenes.hpp"

using namespace glint;

namespace {

std::size_t rays_per_kind() {
    if (const char* e = std::getenv("GLINT_PACKET_RAYS")) return std::size_t(std::strtoull(e, nullptr, 10));
#if defined(GLINT_SANITIZER_TESTS)
    return std::size_t(1) << 11;
#else
    return std::size_t(1) << 14;
#endif
}

/// Primary rays of a square image of about n pixels (row-major).
std::vector<Ray<float>> primary(const Mesh<float>& m, std::size_t n) {
    const int side = std::max(8, int(std::sqrt(double(n))));
    return make_primary_rays<float>(m, side, side);
}

/// Shadow rays from the primary rays' hit points to one point light above the mesh.
template <class Bvh>
std::vector<Ray<float>> shadow(const Bvh& bvh, const Mesh<float>& m, std::size_t n) {
    const auto hit_t = [&](const Ray<float>& r, float& t) {
        StoreHit<float> h;
        const bool hit = bvh.closest_hit(r, h);
        t = h.t;
        return hit;
    };
    return make_light_shadow_rays(primary(m, 8 * n), mesh_bounds<float>(m), hit_t, n);  // the mesh covers part of the image
}

/// Primary rays with invalid rays (NaN, zero direction, infinite origin, tmin > tmax) and
/// intervals starting below 0 mixed in at random places, and a few pre-set hit bounds.
std::vector<Ray<float>> mixed(const Mesh<float>& m, std::size_t n) {
    std::vector<Ray<float>> rays = primary(m, n);
    Pcg32 rng(3);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (auto& r : rays) {
        const std::uint32_t k = rng.bounded(40);
        if (k == 0) r.direction.y = nan;
        else if (k == 1) r.direction = Vec3f(0);
        else if (k == 2) r.origin.x = infinity<float>;
        else if (k == 3) r.tmin = 2.0f, r.tmax = 1.0f;
        else if (k == 4) r.tmin = -infinity<float>;
        else if (k == 5) r.tmin = -1.0f, r.tmax = 1e30f;
        else if (k == 6) r.direction = -r.direction;  // a sign apart from the rest of its packet
    }
    return rays;
}

bool same(const StoreHit<float>& a, const StoreHit<float>& b) {
    return std::bit_cast<std::uint32_t>(a.t) == std::bit_cast<std::uint32_t>(b.t) &&
           std::bit_cast<std::uint32_t>(a.u) == std::bit_cast<std::uint32_t>(b.u) &&
           std::bit_cast<std::uint32_t>(a.v) == std::bit_cast<std::uint32_t>(b.v) && a.id == b.id;
}

/// The stream queries over `rays`, cut into spans of `chunk` rays (the last shorter),
/// against the single-ray queries: the number of rays answered differently.
template <class Bvh>
std::size_t differences(const Bvh& bvh, const std::vector<Ray<float>>& rays, std::size_t chunk) {
    std::vector<StoreHit<float>> hits(rays.size()), ref(rays.size());
    for (std::size_t i = 0; i < rays.size(); i += 97) hits[i].t = ref[i].t = 0.5f * float(i % 7);  // pre-set bounds
    const std::unique_ptr<bool[]> occluded(new bool[rays.size()]);
    std::size_t nhit = 0, nocc = 0;
    for (std::size_t i = 0; i < rays.size(); i += chunk) {
        const std::size_t k = std::min(chunk, rays.size() - i);
        nhit += bvh.closest_hit(std::span(rays).subspan(i, k), std::span(hits).subspan(i, k));
        nocc += bvh.any_hit(std::span(rays).subspan(i, k), std::span(occluded.get() + i, k));
    }
    std::size_t differ = 0, rhit = 0, rocc = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        rhit += bvh.closest_hit(rays[i], ref[i]);
        const bool occ = bvh.any_hit(rays[i]);
        rocc += occ;
        differ += !same(hits[i], ref[i]) || occluded[i] != occ;
    }
    CHECK(nhit == rhit);
    CHECK(nocc == rocc);
    return differ;
}

}  // namespace

/// Every scene, ray kind and kernel through MeshBvh<P>'s streams against its single rays;
/// the packet traversal must have run (coherent primary rays).
template <class P>
void check_streams(std::size_t n) {
    const std::vector<std::pair<const char*, Mesh<float>>> scenes = {
        {"torus-knot", make_torus_knot<float>()},
        {"sphere", make_sphere<float>(40, 80)},
        {"stadium", make_teapot_in_stadium<float>()},
    };
    for (const auto& [name, mesh] : scenes) {
        MeshBvh<P> bvh{std::span<const TriangleVertices<float>>(mesh)};
        const std::vector<std::pair<const char*, std::vector<Ray<float>>>> kinds = {
            {"primary", primary(mesh, n)},
            {"shadow", shadow(bvh, mesh, n)},
            {"incoherent", make_incoherent_rays<float>(mesh, n)},
            {"mixed", mixed(mesh, n)},
        };
        for (Isa isa : all_isas) {
            if (!isa_supported(isa)) continue;
            bvh.set_isa(isa);
            for (const auto& [kind, rays] : kinds) {
                const std::string what = std::string(name) + " " + kind + " " + isa_name(isa);
                CAPTURE(what);
                REQUIRE(rays.size() > n / 4);
                CHECK(differences(bvh, rays, rays.size()) == 0);
                CHECK(differences(bvh, rays, 13) == 0);  // spans that are not whole packets
            }
            std::vector<StoreHit<float>> hits(kinds[0].second.size());
            WideBvhCounters c;
            bvh.closest_hit(kinds[0].second, hits, c);
            CHECK(c.packets > 0);
        }
    }
}

// MeshBvh's default policy tests a leaf with the whole packet (packet_leaf.hpp); Watertight,
// whose ray data is its own, tests each lane with the single-ray leaf test.
static_assert(detail::packet_leaf_supported<MollerTrumbore<float>>);
static_assert(!detail::packet_leaf_supported<Watertight<float>>);

TEST_CASE("packets: streams give the single-ray hits, bit for bit, with every kernel") {
    const std::size_t n = rays_per_kind();
    MESSAGE("rays per scene and kind: " << n << " (GLINT_PACKET_RAYS)");
    check_streams<MollerTrumbore<float>>(n);
}

TEST_CASE("packets: policies without the shared leaf test (Watertight)") {
    check_streams<Watertight<float>>(rays_per_kind() / 4);
}

TEST_CASE("packets: empty streams, an empty tree, and sizes that differ") {
    const Mesh<float> mesh = make_torus_knot<float>(40, 6);
    const MeshBvh<> bvh{std::span<const TriangleVertices<float>>(mesh)};
    const std::vector<Ray<float>> rays = make_primary_rays<float>(mesh, 4, 4);
    std::vector<StoreHit<float>> hits(rays.size() - 1);
    bool occ[16];
    CHECK(bvh.closest_hit(std::span<const Ray<float>>(), std::span<StoreHit<float>>()) == 0);
    try {
        bvh.closest_hit(rays, hits);
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find("16 rays but 15") != std::string::npos);
    }
    CHECK_THROWS_AS(bvh.any_hit(rays, std::span<bool>(occ, 15)), Error);
    const MeshBvh<> empty(std::span<const TriangleVertices<float>>{});
    hits.resize(rays.size());
    CHECK(empty.closest_hit(rays, hits) == 0);
    CHECK(empty.any_hit(rays, std::span<bool>(occ, 16)) == 0);
    for (bool o : occ) CHECK(!o);
}

TEST_CASE("closest_hits / any_hits: a stream through any accelerator (a ray at a time without streams)") {
    const Mesh<float> mesh = make_torus_knot<float>(40, 6);
    const std::span<const TriangleVertices<float>> tris(mesh);
    const MeshBvh<> bvh{tris};
    const BruteForce<MollerTrumbore<float>> brute(tris);
    static_assert(StreamAccelerator<MeshBvh<>> && !StreamAccelerator<BruteForce<MollerTrumbore<float>>>);
    const std::vector<Ray<float>> rays = make_primary_rays<float>(mesh, 24, 24);
    std::vector<StoreHit<float>> a(rays.size()), b(rays.size());
    std::unique_ptr<bool[]> oa(new bool[rays.size()]), ob(new bool[rays.size()]);
    const std::size_t hits = closest_hits(bvh, std::span<const Ray<float>>(rays), std::span<StoreHit<float>>(a));
    CHECK(closest_hits(brute, std::span<const Ray<float>>(rays), std::span<StoreHit<float>>(b)) == hits);
    CHECK(hits > rays.size() / 20);  // a good number hit (83 of 576)
    CHECK(hits < rays.size());  // some rays miss
    CHECK(any_hits(bvh, std::span<const Ray<float>>(rays), std::span<bool>(oa.get(), rays.size())) == hits);
    CHECK(any_hits(brute, std::span<const Ray<float>>(rays), std::span<bool>(ob.get(), rays.size())) == hits);
    for (std::size_t i = 0; i < rays.size(); ++i) {
        CHECK(a[i].id == b[i].id);
        CHECK(a[i].found() == oa[i]);
        CHECK(oa[i] == ob[i]);
    }
    b.pop_back();
    CHECK_THROWS_WITH_AS(closest_hits(brute, std::span<const Ray<float>>(rays), std::span<StoreHit<float>>(b)),
                         doctest::Contains("576 rays but 575"), Error);
    CHECK_THROWS_WITH_AS(any_hits(brute, std::span<const Ray<float>>(rays), std::span<bool>(ob.get(), 3)),
                         doctest::Contains("576 rays but 3"), Error);
}

TEST_CASE("MeshBvh<P, 4>: streams a ray at a time, the single rays' hits") {
    const Mesh<float> mesh = make_torus_knot<float>(40, 6);
    const MeshBvh<MollerTrumbore<float>, 4> bvh{std::span<const TriangleVertices<float>>(mesh)};
    static_assert(!MeshBvh<MollerTrumbore<float>, 4>::packets && MeshBvh<>::packets);
    const std::vector<Ray<float>> rays = make_primary_rays<float>(mesh, 24, 24);
    std::vector<StoreHit<float>> hits(rays.size());
    std::unique_ptr<bool[]> occ(new bool[rays.size()]);
    const std::size_t n = bvh.closest_hit(rays, hits);
    CHECK(bvh.any_hit(rays, std::span<bool>(occ.get(), rays.size())) == n);
    CHECK(n > rays.size() / 20);
    for (std::size_t i = 0; i < rays.size(); ++i) {
        StoreHit<float> h;
        CHECK(bvh.closest_hit(rays[i], h) == hits[i].found());
        CHECK((h.id == hits[i].id && h.t == hits[i].t && h.u == hits[i].u && h.v == hits[i].v));
        CHECK(occ[i] == hits[i].found());
    }
}
