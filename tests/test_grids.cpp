// Tests of the uniform grid and the octree (trees/uniform_grid.hpp, trees/octree.hpp), the
// baselines of bench_grids.
//
// Agreement, exact: through a Möller-Trumbore leaf callable (tests/support/cell_leaves.hpp),
// the closest hit is the same triangle with the same t, u and v (bit for bit) as
// BruteForce<MollerTrumbore<float>> gives, and any hit the same answer, on generated meshes
// (the torus knot, a triangle soup with zero-area triangles, the teapot in a stadium; not the
// UV sphere, whose pole triangles are slivers 1e-16 wide on which float Möller-Trumbore
// reports hits far outside the triangles' boxes, where no cell can hold them) with incoherent and primary rays, random rays starting inside and outside the box
// (half with finite random intervals), rays parallel to the axes through vertex coordinates
// and along the grid's cell planes (grazing cell boundaries), and rays that miss the box.
// Both sides run the same record arithmetic and break ties in t by the lower triangle index,
// so nothing is tolerated. Stress: empty meshes, unhittable triangles only, one triangle, a
// flat grid with rays in its plane, NaN and zero rays, bad options.
// Under the sanitizers (-DGLINT_SANITIZER_TESTS): 500 rays per kind instead of 2000.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/random.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/trees/brute_force.hpp>
#include <glint/trees/octree.hpp>
#include <glint/trees/uniform_grid.hpp>

#include "cell_leaves.hpp"
#include "tree_scenes.hpp"

using namespace glint;

namespace {

#if defined(GLINT_SANITIZER_TESTS)
constexpr std::size_t rays_per_kind = 500;
#else
constexpr std::size_t rays_per_kind = 2000;
#endif

using Brute = BruteForce<MollerTrumbore<float>>;

/// Random rays with origins in the scene's box grown by half its size on each side (so inside
/// and outside), uniform directions; every other one gets a finite random interval.
std::vector<Ray<float>> random_rays(const AABB<float>& b, std::size_t n, std::uint64_t seed) {
    Pcg32 rng(seed);
    const Vec3f e = b.extent();
    std::vector<Ray<float>> rays;
    for (std::size_t i = 0; i < n; ++i) {
        Ray<float> r;
        for (int a = 0; a < 3; ++a) r.origin[a] = b.lo[a] + e[a] * (2.0f * rng.uniform<float>() - 0.5f);
        const float z = 2.0f * rng.uniform<float>() - 1.0f, phi = 6.2831853f * rng.uniform<float>();
        const float s = std::sqrt(std::max(0.0f, 1.0f - z * z));
        r.direction = Vec3f(s * std::cos(phi), s * std::sin(phi), z);
        if (i % 2) {
            const float len = glm::length(e);
            r.tmin = len * (rng.uniform<float>() - 0.25f);
            r.tmax = r.tmin + 2.0f * len * rng.uniform<float>();
        }
        rays.push_back(r);
    }
    return rays;
}

/// Rays along +-x, +-y or +-z whose other two coordinates are vertex coordinates of the mesh,
/// or (every other one) planes of `grid`'s cells: through vertices and edges, and grazing cell
/// boundaries. Origins start outside the box, inside it, or (one in eight) point away from it.
std::vector<Ray<float>> axis_rays(const Mesh<float>& m, const UniformGrid<float>& grid, std::size_t n, std::uint64_t seed) {
    Pcg32 rng(seed);
    const AABB<float> b = grid.bounds();
    const auto res = grid.resolution();
    std::vector<Ray<float>> rays;
    for (std::size_t i = 0; i < n; ++i) {
        const int axis = int(rng.uniform<float>() * 3) % 3;
        const float sign = rng.uniform<float>() < 0.5f ? -1.0f : 1.0f;
        const Vec3f v = m[std::size_t(rng.uniform<float>() * float(m.size())) % m.size()][i % 3];
        Ray<float> r;
        for (int a = 0; a < 3; ++a) {
            const std::uint32_t cells = res[std::size_t(a)];
            const int cell = int(rng.uniform<float>() * float(cells + 1));
            r.origin[a] = i % 2 ? v[a] : b.lo[a] + (b.hi[a] - b.lo[a]) * float(cell) / float(cells);
        }
        const float span = b.hi[axis] - b.lo[axis] + 1.0f;
        r.origin[axis] = i % 4 < 2 ? (sign > 0 ? b.lo[axis] - span : b.hi[axis] + span) : b.lo[axis] + 0.5f * span;
        if (i % 8 == 7) r.origin[axis] = sign > 0 ? b.hi[axis] + span : b.lo[axis] - span;  // points away: a miss
        r.direction = Vec3f(0);
        r.direction[axis] = sign;
        rays.push_back(r);
    }
    return rays;
}

/// Closest and any hit of `acc` (through the Möller-Trumbore leaf callable) equal brute force's.
template <class Accel>
void check_rays(const std::string& what, const Mesh<float>& m, const Accel& acc, const std::vector<Ray<float>>& rays) {
    const Brute brute(m);
    const TriangleCells cells(m);
    std::size_t hits = 0, wrong = 0, wrong_any = 0;
    for (const Ray<float>& r : rays) {
        StoreHit<float> want, got;
        const bool w = brute.closest_hit(r, want), g = cells.closest_hit(acc, r, got);
        hits += w;
        const bool same = w == g && (!w || (want.id == got.id && want.t == got.t && want.u == got.u && want.v == got.v));
        if (!same && ++wrong <= 3)
            MESSAGE(what << ": ray o=(" << r.origin.x << ", " << r.origin.y << ", " << r.origin.z << ") d=(" << r.direction.x
                         << ", " << r.direction.y << ", " << r.direction.z << "): brute force " << std::string(w ? "hits " : "misses ")
                         << want.id << " at " << want.t << ", the accelerator " << std::string(g ? "hits " : "misses ")
                         << got.id << " at " << got.t);
        wrong_any += brute.any_hit(r) != cells.any_hit(acc, r);
    }
    INFO(what << ": " << rays.size() << " rays, " << hits << " hits");
    CHECK(wrong == 0);
    CHECK(wrong_any == 0);
}

/// Both accelerators over `m` against brute force on every kind of ray.
void check_scene(const std::string& name, const Mesh<float>& m) {
    const TriangleCells cells(m);
    const UniformGrid<float> grid(cells.boxes(), {}, cells.overlap_test());
    const Octree<float> octree(cells.boxes(), {}, cells.overlap_test());
    std::vector<Ray<float>> rays = make_incoherent_rays<float>(m, rays_per_kind);
    const auto primary = make_primary_rays<float>(m, 50, int(rays_per_kind / 50));
    const auto random = random_rays(grid.bounds(), rays_per_kind, 5);
    const auto axes = axis_rays(m, grid, rays_per_kind, 9);
    for (const auto* set : {&primary, &random, &axes}) rays.insert(rays.end(), set->begin(), set->end());
    check_rays(name + " grid", m, grid, rays);
    check_rays(name + " octree", m, octree, rays);
}

}  // namespace

TEST_CASE("agreement: grid and octree against brute force, exact") {
    check_scene("torus knot", make_torus_knot<float>());
    Mesh<float> soup = make_soup<float>(3000);
    for (std::size_t i = 0; i < 100; ++i) soup[i * 30][2] = soup[i * 30][1];  // zero area: never binned, never hit
    check_scene("soup", soup);
    check_scene("stadium", make_teapot_in_stadium<float>());
}

TEST_CASE("agreement: other resolutions and leaf sizes") {
    const Mesh<float> m = make_torus_knot<float>(60, 8);
    const TriangleCells cells(m);
    const auto rays = random_rays(mesh_bounds<float>(m), rays_per_kind, 21);
    for (double density : {0.05, 1.0, 30.0}) {
        const UniformGrid<float> grid(cells.boxes(), {.cells_per_primitive = density}, cells.overlap_test());
        check_rays("grid, " + std::to_string(density) + " cells per triangle", m, grid, rays);
    }
    const UniformGrid<float> boxes_only(cells.boxes());  // binned by box overlap alone
    check_rays("grid by boxes", m, boxes_only, rays);
    for (std::uint32_t leaf : {1u, 32u}) {
        const Octree<float> octree(cells.boxes(), {.max_leaf = leaf, .max_depth = 6}, cells.overlap_test());
        check_rays("octree, leaves of " + std::to_string(leaf), m, octree, rays);
    }
    check_rays("octree by boxes", m, Octree<float>(cells.boxes()), rays);
}

TEST_CASE("resolution, references and counting hooks") {
    const Mesh<float> m = make_torus_knot<float>();
    const TriangleCells cells(m);
    const UniformGrid<float> grid(cells.boxes(), {}, cells.overlap_test());
    const auto res = grid.resolution();
    const double total = double(res[0]) * res[1] * res[2];
    CHECK(total == doctest::Approx(4.0 * double(m.size())).epsilon(0.5));  // about 4 cells per triangle
    CHECK(grid.cell_count() == std::size_t(total));
    CHECK(grid.prims().size() >= m.size());  // every triangle binned at least once
    const Octree<float> octree(cells.boxes(), {}, cells.overlap_test());
    CHECK(octree.nodes().size() % 8 == 1);  // the root and eight children per inner node
    // A ray through the middle visits cells and tests triangles, and finds brute force's hit.
    Ray<float> r;
    r.origin = grid.bounds().center() - Vec3f(10, 0.01f, 0.02f);
    r.direction = Vec3f(1, 0, 0);
    std::size_t visited = 0, tests = 0;
    StoreHit<float> got, want;
    const bool g = cells.closest_hit(grid, r, got, [&] { ++tests; }, [&] { ++visited; });
    CHECK(g == Brute(m).closest_hit(r, want));
    CHECK(got.id == want.id);
    CHECK(visited > 0);
    CHECK(tests > 0);
}

TEST_CASE("stress: empty, unhittable, one triangle, flat, bad rays, bad options") {
    const Mesh<float> none;
    const TriangleCells no_cells(none);
    const UniformGrid<float> empty_grid(no_cells.boxes());
    const Octree<float> empty_octree(no_cells.boxes());
    Ray<float> r;
    StoreHit<float> h;
    CHECK(empty_grid.cell_count() == 0);
    CHECK_FALSE(no_cells.closest_hit(empty_grid, r, h));
    CHECK_FALSE(no_cells.any_hit(empty_octree, r));
    CHECK_FALSE(no_cells.closest_hit(UniformGrid<float>{}, r, h));

    const Vec3f p(1, 2, 3);
    const Mesh<float> flat_only{{p, p, p}, {p, p + Vec3f(1, 0, 0), p + Vec3f(2, 0, 0)}};  // zero area
    const TriangleCells flat_cells(flat_only);
    CHECK(UniformGrid<float>(flat_cells.boxes()).cell_count() == 0);
    CHECK(Octree<float>(flat_cells.boxes()).nodes().empty());

    const Mesh<float> one{{Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)}};
    const TriangleCells one_cells(one);
    const UniformGrid<float> g1(one_cells.boxes(), {}, one_cells.overlap_test());
    CHECK(g1.resolution()[2] == 1);
    check_rays("one triangle grid", one, g1, random_rays(AABB<float>{Vec3f(-1), Vec3f(2)}, 500, 3));
    check_rays("one triangle octree", one, Octree<float>(one_cells.boxes(), {}, one_cells.overlap_test()),
               random_rays(AABB<float>{Vec3f(-1), Vec3f(2)}, 500, 3));

    // A flat grid: rays in its plane (parallel to z = 0, hitting nothing: det = 0) and through it.
    const Mesh<float> flat = make_flat_grid<float>(20);
    const TriangleCells fc(flat);
    const UniformGrid<float> fg(fc.boxes(), {}, fc.overlap_test());
    const Octree<float> fo(fc.boxes(), {}, fc.overlap_test());
    std::vector<Ray<float>> rays = axis_rays(flat, fg, 400, 4);
    for (const auto& x : random_rays(fg.bounds(), 400, 8)) rays.push_back(x);
    check_rays("flat grid", flat, fg, rays);
    check_rays("flat octree", flat, fo, rays);

    Ray<float> bad;
    bad.origin = Vec3f(0.5f, 0.5f, 1);
    bad.direction = Vec3f(0);
    CHECK_FALSE(fc.closest_hit(fg, bad, h));
    bad.direction = Vec3f(0, 0, std::numeric_limits<float>::quiet_NaN());
    CHECK_FALSE(fc.any_hit(fo, bad));
    bad.direction = Vec3f(0, 0, -1);
    bad.tmax = std::numeric_limits<float>::quiet_NaN();
    CHECK_FALSE(fc.closest_hit(fg, bad, h));
    CHECK_FALSE(fc.closest_hit(fo, bad, h));

    CHECK_THROWS_AS(UniformGrid<float>(fc.boxes(), {.cells_per_primitive = 0}), Error);
    CHECK_THROWS_AS(UniformGrid<float>(fc.boxes(), {.max_resolution = 0}), Error);
    CHECK_THROWS_AS(Octree<float>(fc.boxes(), {.max_leaf = 0}), Error);
    CHECK_THROWS_AS(Octree<float>(fc.boxes(), {.max_depth = 21}), Error);
}
