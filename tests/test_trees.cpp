// Tests of glint/trees: builders, layouts, traversal against brute force, memory claims.
//
// Agreement: every tree (kd, BIH) x layout x intersector returns the same closest hit as
// BruteForce with the same intersector. "Same" means: the same triangle with t within
// t_tol (1e-4 relative, plus the rounding of the coordinates divided by the incidence
// cosine), or a tie (another triangle at t within t_tol, whose plane and bounding box hold the
// hit point within t_tol: a wrong triangle id with the right t fails). A disagreement is otherwise
// allowed only when the nearer reported hit lies on its triangle's boundary (barycentric
// distance below edge_tol: 1e-4 plus the coordinates' rounding relative to the triangle's
// size) or at one of its vertices (within t_tol: needle triangles' barycentrics are
// ill-conditioned), or its t lies within t_tol of the ray's tmin or tmax (found by the 10^6-ray runs:
// rays starting 10^-4 above the stadium's ground, 1000 units from the frame origin), where
// the tree and brute force may legitimately round differently: IVM records
// live in a frame per leaf in the tree and per triangle in brute force, and with FMA
// contraction (-march=native) the compiler may fuse the other kernels differently where
// they are inlined. On the generic rays at most 1 in 1000 may be such an edge case; the
// adversarial rays (axis-parallel through vertex coordinates) may have any number, but
// every one must be an edge case. Nothing else is tolerated.
//
// CI runs 2 * 10^4 rays per scene and combination, and the trees' kinds and layouts times the
// intersectors pairwise instead of as a product (every layout with Moller-Trumbore, every
// intersector in the pointer layout and the 8-wide BVH): each traversal and each leaf test is
// still compiled and run, with 23 tree types instead of 56 (the product was the largest
// compile of the whole build). -DGLINT_LONG_TESTS runs the full product and 10^6 rays (for
// the wide BVH alone: test_trees -tc="agreement: wide*", or one kind of it, e.g.
// -tc="*spatial*"). Under the sanitizers (-DGLINT_SANITIZER_TESTS), which look for memory
// errors, not rare edge cases: 4000 rays.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/wald.hpp>
#include <glint/intersection/watertight.hpp>
#include <glint/trees/brute_force.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include "tree_scenes.hpp"
#include <glint/trees/traversal.hpp>

using namespace glint;

namespace {

/// Type X as the compiler spells it, for INFO messages (the library's types carry no labels).
template <class X>
std::string type_label() {
    const std::string f = __PRETTY_FUNCTION__;  // "... [with X = glint::Ivm<float>; ...]" or "... [X = ...]"
    const std::size_t b = f.find("X = ") + 4;
    return f.substr(b, f.find_first_of(";]", b) - b);
}

#if defined(GLINT_LONG_TESTS)
constexpr std::size_t rays_per_scene = 1'000'000;
#elif defined(GLINT_SANITIZER_TESTS)
constexpr std::size_t rays_per_scene = 4'000;  // under ASan (25x slower): memory errors, not rare edge cases
#else
constexpr std::size_t rays_per_scene = 20'000;
#endif

struct Scene {
    std::string name;
    Mesh<float> mesh;
    std::vector<Ray<float>> rays;
    std::size_t generic = 0;  // rays[0, generic) are generic, the rest vertex-snapped
    double scale = 0;         // |extent| + |centre| of the scene's box
};

/// A mix of ray kinds over one scene. Generic: incoherent surface rays, primary camera
/// rays, rays starting anywhere in (and around) the scene box in random directions, half of
/// them with finite random tmin/tmax (half of those starting below 0, so that boxes behind
/// the origin are entered). Then (one ray in six) adversarial axis-parallel rays whose other
/// two coordinates are vertex coordinates, so that they lie in split planes and run through
/// triangle edges and vertices, and through flat boxes; a quarter of them are whole lines
/// (tmin = -inf).
std::vector<Ray<float>> ray_mix(const Mesh<float>& m, std::size_t n, std::uint64_t seed, std::size_t& generic) {
    std::vector<Ray<float>> rays = make_incoherent_rays<float>(m, n / 4, seed);
    const auto prim = make_primary_rays<float>(m, 100, int(n / 8 / 100) + 1, seed + 1);
    rays.insert(rays.end(), prim.begin(), prim.end());
    const AABB<float> b = mesh_bounds<float>(m);
    const Vec3f lo = b.lo - 0.1f * b.extent(), ext = 1.2f * b.extent();
    Pcg32 rng(seed + 2);
    auto u = [&] { return rng.uniform<float>(); };
    auto sphere_dir = [&] {
        const float z = 2 * u() - 1, phi = 2 * pi<float> * u(), r = std::sqrt(std::max(0.f, 1 - z * z));
        return Vec3f(r * std::cos(phi), r * std::sin(phi), z);
    };
    const float size = glm::length(b.extent());
    generic = n - n / 6;
    while (rays.size() < n) {
        Ray<float> r;
        r.origin = lo + Vec3f(u(), u(), u()) * ext;
        r.direction = sphere_dir();
        if (rays.size() >= generic) {  // axis-parallel, origin on vertex coordinates
            const auto& t = m[rng.bounded(std::uint32_t(m.size()))];
            const int a = int(rng.bounded(3));
            for (int k = 0; k < 3; ++k)
                if (k != a) r.origin[k] = t[rng.bounded(3)][k];
            r.direction = Vec3f(0);
            r.direction[a] = u() < 0.5f ? -1.f : 1.f;
            if (u() < 0.5f) r.direction[(a + 1) % 3] = -0.f;
            if (u() < 0.25f) r.tmin = -infinity<float>;
        } else if (u() < 0.5f) {  // finite interval, half of them starting below 0
            r.tmin = (u() - 0.5f) * size;
            r.tmax = r.tmin + u() * size;
        }
        rays.push_back(r);
    }
    rays.resize(n);
    return rays;
}

const std::vector<Scene>& scenes() {
    static const std::vector<Scene> s = [] {
        std::vector<Scene> v;
        v.push_back({"sphere", make_sphere<float>(40, 80), {}, 0, 0});
        v.push_back({"torus-knot", make_torus_knot<float>(), {}, 0, 0});
        v.push_back({"soup", make_soup<float>(3000, 5), {}, 0, 0});
        v.push_back({"stadium", make_teapot_in_stadium<float>(), {}, 0, 0});
        std::uint64_t seed = 100;
        for (auto& sc : v) {
            sc.rays = ray_mix(sc.mesh, rays_per_scene, seed += 10, sc.generic);
            const AABB<float> b = mesh_bounds<float>(sc.mesh);
            sc.scale = glm::length(Vec3d(b.extent())) + glm::length(Vec3d(b.center()));
        }
        return v;
    }();
    return s;
}

/// Smallest barycentric coordinate of the ray's hit with triangle `tri`, in double,
/// relative to the triangle: below 1e-4 the hit is "on an edge".
double edge_distance(const TriangleVertices<float>& tri, const Ray<float>& r, double t) {
    const Vec3d a(tri[0]), b(tri[1]), c(tri[2]);
    const Vec3d p = Vec3d(r.origin) + t * Vec3d(r.direction);
    const Vec3d n = glm::cross(b - a, c - a);
    const double nn = glm::dot(n, n);
    if (!(nn > 0)) return 0;
    const double w0 = glm::dot(glm::cross(c - b, p - b), n) / nn;
    const double w1 = glm::dot(glm::cross(a - c, p - c), n) / nn;
    return std::min({w0, w1, 1 - w0 - w1});
}

struct Tally {
    std::size_t rays = 0, hits = 0, ties = 0, edges = 0, generic_rays = 0, generic_edges = 0, degenerate = 0,
                errors = 0;
};

/// Magnitude of the coordinates a scene's computations round at: |extent| + |centre|.
double scene_scale(const Scene& sc) { return sc.scale; }

/// t tolerance: 1e-4 relative, plus the rounding of the hit's distance from the plane
/// (32 float ulps of the coordinates' magnitude |origin| + scene scale) divided by the
/// cosine of the incidence angle: at grazing incidence a tiny error across the plane is a
/// large error along the ray. (IVM's frames, one per leaf in a tree and one per triangle in
/// brute force, round differently; with FMA contraction the other kernels can too.)
float t_tol(const Scene& sc, const Ray<float>& r, const TriangleVertices<float>& tri, float t) {
    const Vec3d n = safe_normalize(glm::cross(Vec3d(tri[1] - tri[0]), Vec3d(tri[2] - tri[0])));
    const double cosine = std::abs(glm::dot(n, Vec3d(r.direction))) + 1e-30;
    return float(1e-4 * std::max(1.0, double(t)) +
                 32 * 0x1p-24 * (glm::length(Vec3d(r.origin)) + scene_scale(sc)) / cosine);
}

/// Barycentric distance below which a hit counts as on an edge: 1e-4, plus 64 float ulps of
/// the coordinates' magnitude relative to the triangle's size.
double edge_tol(const Scene& sc, const Ray<float>& r, const TriangleVertices<float>& tri) {
    const double size = std::sqrt(glm::length(glm::cross(Vec3d(tri[1] - tri[0]), Vec3d(tri[2] - tri[0])))) + 1e-30;
    return 1e-4 + 64 * 0x1p-24 * (glm::length(Vec3d(r.origin)) + scene_scale(sc)) / size;
}

/// Whether the ray, in double precision, crosses some triangle of the scene within
/// edge_tol of that triangle's boundary (inside or just outside) for t in (tmin, tmax), or
/// inside it at a t within t_tol of tmin or tmax.
bool boundary_crossing(const Scene& sc, const Ray<float>& r) {
    const Vec3d o(r.origin), d(r.direction);
    for (const auto& tri : sc.mesh) {
        const Vec3d a(tri[0]), b(tri[1]), c(tri[2]);
        const Vec3d n = glm::cross(b - a, c - a);
        const double nn = glm::dot(n, n), dn = glm::dot(d, n);
        if (!(nn > 0) || dn == 0) continue;
        const double t = glm::dot(a - o, n) / dn;
        const double slack = t_tol(sc, r, tri, float(t));
        if (!(t > double(r.tmin) - slack && t < double(r.tmax) + slack)) continue;
        const double w = edge_distance(tri, r, t);
        if (std::abs(w) < edge_tol(sc, r, tri)) return true;  // near the triangle's boundary
        if (w > 0 && (std::abs(t - double(r.tmin)) <= slack || std::abs(double(r.tmax) - t) <= slack))
            return true;  // inside, near an end of the ray's interval
    }
    return false;
}

/// Whether the point the ray reaches at t is one of the triangle's vertices, up to t_tol. A
/// needle triangle's plane and barycentrics are ill-conditioned (the UV sphere's pole rows,
/// met by rays along the axis through the pole), but a hit at its vertex is a boundary hit.
bool near_vertex(const Scene& sc, const Ray<float>& r, const TriangleVertices<float>& tri, float t) {
    const Vec3d p = Vec3d(r.origin) + double(t) * Vec3d(r.direction);
    const double tol = double(t_tol(sc, r, tri, t)) * glm::length(Vec3d(r.direction));
    for (const auto& v : tri)
        if (glm::length(p - Vec3d(v)) <= tol) return true;
    return false;
}

/// Whether the point the ray reaches at t lies on triangle `tri`, up to the tolerance of t
/// (t_tol, in distance along the ray): within that distance of the triangle's plane and of
/// its bounding box. Used to check a tie's triangle; the box, not the barycentrics, because
/// ties at a vertex shared with a needle triangle (the UV sphere's poles) are legitimate.
bool on_triangle(const Scene& sc, const Ray<float>& r, const TriangleVertices<float>& tri, float t) {
    if (near_vertex(sc, r, tri, t)) return true;
    const Vec3d a(tri[0]), d(r.direction);
    const Vec3d p = Vec3d(r.origin) + double(t) * d;
    const Vec3d n = glm::cross(Vec3d(tri[1]) - a, Vec3d(tri[2]) - a);
    const double nl = glm::length(n);
    const double tol = double(t_tol(sc, r, tri, t)) * glm::length(d);
    if (!(nl > 0) || std::abs(glm::dot(n, p - a)) / nl > tol) return false;
    for (int k = 0; k < 3; ++k) {
        const double lo = std::min({double(tri[0][k]), double(tri[1][k]), double(tri[2][k])});
        const double hi = std::max({double(tri[0][k]), double(tri[1][k]), double(tri[2][k])});
        if (p[k] < lo - tol || p[k] > hi + tol) return false;
    }
    return true;
}

bool zero_area(const TriangleVertices<float>& t) {
    const Vec3d n = glm::cross(Vec3d(t[1]) - Vec3d(t[0]), Vec3d(t[2]) - Vec3d(t[0]));
    return n == Vec3d(0);
}

/// Classifies one disagreement (or agreement) between a tree's hit and the reference's.
void compare(const Scene& sc, std::size_t i, const StoreHit<float>& h, bool found, const StoreHit<float>& ref,
             bool ref_found, Tally& tally) {
    const Ray<float>& r = sc.rays[i];
    const bool generic = i < sc.generic;
    ++tally.rays;
    tally.generic_rays += generic;
    tally.hits += ref_found;
    const float tol = ref_found ? t_tol(sc, r, sc.mesh[ref.id], ref.t) : 0.f;
    if (found == ref_found && (!found || (h.id == ref.id && std::abs(h.t - ref.t) <= tol))) return;
    // A tie: the tree's triangle must itself be hit there (its plane within t_tol of h.t, the
    // point inside it or within edge_tol of its boundary), not just report the right t.
    if (found && ref_found && std::abs(h.t - ref.t) <= tol && on_triangle(sc, r, sc.mesh[h.id], h.t)) {
        ++tally.ties;
        return;
    }
    // The reference hit a zero-area triangle, which the intersector contract says never
    // hits and the builders leave out: an intersector defect, counted and shown, not a
    // tree error.
    if (ref_found && zero_area(sc.mesh[ref.id]) && (!found || h.t >= ref.t)) {
        ++tally.degenerate;
        return;
    }
    {
        // The nearer of the two reported hits decides; it must be on an edge.
        const bool tree_nearer = found && (!ref_found || h.t < ref.t);
        const StoreHit<float>& near = tree_nearer ? h : ref;
        const auto& tri = sc.mesh[near.id];
        const float near_tol = t_tol(sc, r, tri, near.t);
        const bool at_interval_end = near.t - r.tmin <= near_tol || r.tmax - near.t <= near_tol;
        // |distance|: a point outside the triangle (negative distance) is not an edge case.
        if (std::abs(edge_distance(tri, r, near.t)) < edge_tol(sc, r, tri) || near_vertex(sc, r, tri, near.t) ||
            at_interval_end) {
            ++tally.edges;
            tally.generic_edges += generic;
            return;
        }
    }
    if (++tally.errors <= 5)
        std::printf("  mismatch: o=(%.9g %.9g %.9g) d=(%.9g %.9g %.9g) [%g %g] tree %d id %u t %.9g  ref %d id %u t %.9g\n",
                    r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y, r.direction.z, r.tmin, r.tmax,
                    found, h.id, h.t, ref_found, ref.id, ref.t);
}

template <class Accel, class P>
void check_agreement(const Scene& sc, const std::vector<StoreHit<float>>& ref, const std::vector<char>& ref_found) {
    const Accel tree(sc.mesh);
    Tally closest, any;
    for (std::size_t i = 0; i < sc.rays.size(); ++i) {
        const Ray<float>& r = sc.rays[i];
        StoreHit<float> h;
        const bool found = tree.closest_hit(r, h);
        compare(sc, i, h, found, ref[i], ref_found[i], closest);
        // Any hit agrees with the tree's own closest-hit occlusion, on the full ray and on a
        // shadow ray that ends halfway to the closest hit (and so with brute force, up to
        // the cases classified above). The same kernel, inlined into the any-hit and the
        // closest-hit traversal, may be compiled differently (vectorized or not, FMA
        // contraction) and round an exact edge or vertex hit differently, so a disagreement
        // is allowed only where the ray (computed in double) crosses some triangle within
        // edge_tol of its boundary or near an end of its interval; at most 1 in 1000 generic
        // rays may be one.
        const bool generic = i < sc.generic;
        auto check_any = [&](const Ray<float>& ray, bool occluded, bool closest_found) {
            ++any.rays;
            if (occluded == closest_found) return;
            if (!boundary_crossing(sc, ray)) ++any.errors;
            ++any.edges;
            any.generic_edges += generic;
        };
        check_any(r, tree.any_hit(r), found);
        if (found) {
            Ray<float> shadow = r;
            shadow.tmax = r.tmin + 0.5f * (h.t - r.tmin);
            StoreHit<float> hs;
            check_any(shadow, tree.any_hit(shadow), tree.closest_hit(shadow, hs));
        }
    }
    INFO(sc.name << " " << type_label<Accel>());
    INFO("closest: rays " << closest.rays << " hits " << closest.hits << " ties " << closest.ties << " edges "
                          << closest.edges << " (generic " << closest.generic_edges << " of " << closest.generic_rays
                          << ") reference hits on zero-area triangles " << closest.degenerate << " errors "
                          << closest.errors);
    INFO("any: rays " << any.rays << " disagreements at triangle boundaries " << any.edges << " (on generic rays "
                      << any.generic_edges << ") errors " << any.errors);
    CHECK(closest.errors == 0);
    CHECK(any.errors == 0);
    CHECK(any.generic_edges * 1000 <= closest.generic_rays);
    CHECK(closest.generic_edges * 1000 <= closest.generic_rays);
    CHECK(closest.hits > closest.rays / 10);  // the ray sets do hit things
    CHECK(closest.degenerate == 0);  // the intersector contract: zero-area triangles never hit
}

template <class P, template <class, class, class> class Tree, class... Layouts>
void check_layouts(const Scene& sc, const std::vector<StoreHit<float>>& ref, const std::vector<char>& found) {
    (check_agreement<Tree<float, P, Layouts>, P>(sc, ref, found), ...);
}

/// Brute force's closest hits of every scene's rays with intersector P, computed once and
/// shared by the kd-tree/BIH and the wide-BVH agreement tests.
struct BruteReference {
    std::vector<StoreHit<float>> hits;
    std::vector<char> found;
};

template <class P>
const BruteReference& brute_reference(std::size_t scene) {
    static const std::vector<BruteReference> refs = [] {
        std::vector<BruteReference> out;
        for (const Scene& sc : scenes()) {
            const BruteForce<P> bf(sc.mesh);
            BruteReference r{std::vector<StoreHit<float>>(sc.rays.size()), std::vector<char>(sc.rays.size())};
            for (std::size_t i = 0; i < sc.rays.size(); ++i) r.found[i] = bf.closest_hit(sc.rays[i], r.hits[i]);
            out.push_back(std::move(r));
        }
        return out;
    }();
    return refs[scene];
}

template <class P>
void check_intersector() {
    for (std::size_t s = 0; s < scenes().size(); ++s) {
        const Scene& sc = scenes()[s];
        const std::vector<StoreHit<float>>& ref = brute_reference<P>(s).hits;
        const std::vector<char>& found = brute_reference<P>(s).found;
#if !defined(GLINT_LONG_TESTS)
        if constexpr (!std::is_same_v<P, MollerTrumbore<float>>) {  // the other intersectors in one layout each
            check_layouts<P, KdTree, PointerLayout>(sc, ref, found);
            check_layouts<P, Bih, PointerLayout>(sc, ref, found);
        } else
#endif
        {
            check_layouts<P, KdTree, PointerLayout, HavranSubtrees<7>, CompactSubtrees<3>, CompactSubtrees<31>,
                          HavranSubtrees<63>>(sc, ref, found);
            check_layouts<P, Bih, PointerLayout, HavranSubtrees<31>, CompactSubtrees<7>, CompactSubtrees<63>>(sc, ref, found);
        }
    }
}

/// The 8-wide BVH with spatial splits at every node (BvhBuildOptions::full_spatial_splits).
template <class P>
struct SpatialBvh8 : MeshBvh<P, 8> {
    explicit SpatialBvh8(const Mesh<float>& m)
        : MeshBvh<P, 8>(std::span<const TriangleVertices<float>>(m), BvhBuildOptions::full_spatial_splits()) {}
};

/// The 8-wide BVH with spatial splits in the top levels (BvhBuildOptions::top_spatial_splits),
/// tried at every top node (no node overlap needed) so that the test scenes split.
template <class P>
struct TopSpatialBvh8 : MeshBvh<P, 8> {
    static BvhBuildOptions options() {
        BvhBuildOptions o = BvhBuildOptions::top_spatial_splits();
        o.spatial_node_overlap = 0.0f;
        return o;
    }
    explicit TopSpatialBvh8(const Mesh<float>& m) : MeshBvh<P, 8>(std::span<const TriangleVertices<float>>(m), options()) {}
};

template <class P>
using WideBvh8 = MeshBvh<P, 8>;
template <class P>
using WideBvh4 = MeshBvh<P, 4>;
template <class P>
using QuantizedBvh8 = MeshBvh<P, 8, WideBoxes::quantized>;  // 4 wide: the user-leaf test
template <class P>
using CompactBvh8 = MeshBvh<P, 8, WideBoxes::floats, WideCompactSubtrees<18>>;

/// One kind of wide BVH against brute force, for every intersector: the same rules and rays
/// as the other trees, 10^6 per scene with GLINT_LONG_TESTS.
template <template <class> class Tree>
void check_wide() {
    auto check = [&]<class P>() {
        for (std::size_t s = 0; s < scenes().size(); ++s)
            check_agreement<Tree<P>, P>(scenes()[s], brute_reference<P>(s).hits, brute_reference<P>(s).found);
    };
    check.template operator()<MollerTrumbore<float>>();
#if !defined(GLINT_LONG_TESTS)
    if constexpr (!std::is_same_v<Tree<Ivm<float>>, MeshBvh<Ivm<float>, 8>>) return;  // the others in the 8-wide BVH only
    else
#endif
    {
        check.template operator()<Ivm<float>>();
        check.template operator()<Wald<float>>();
        check.template operator()<Watertight<float>>();
    }
}

}  // namespace

TEST_CASE("exact: one triangle, hit point and miss") {
    const Mesh<float> m{{Vec3f(0, 0, 1), Vec3f(1, 0, 1), Vec3f(0, 1, 1)}};
    const KdTree<float, MollerTrumbore<float>, CompactSubtrees<7>> kd(m);
    const Bih<float, Wald<float>, PointerLayout> bih(m);
    Ray<float> r;
    r.origin = Vec3f(0.25f, 0.25f, 0);
    r.direction = Vec3f(0, 0, 2);
    StoreHit<float> h1, h2;
    CHECK(kd.closest_hit(r, h1));
    CHECK(bih.closest_hit(r, h2));
    CHECK(h1.t == doctest::Approx(0.5f));
    CHECK(h2.t == doctest::Approx(0.5f));
    CHECK(h1.id == 0);
    r.tmax = 0.4f;
    CHECK_FALSE(kd.any_hit(r));
    r.origin.x = 2;
    r.tmax = infinity<float>;
    CHECK_FALSE(kd.any_hit(r));
}

TEST_CASE("exact: kd-tree of two separated triangles splits between them") {
    Mesh<float> m;
    for (int i = 0; i < 64; ++i) {
        const float x = i < 32 ? 0.f : 10.f;
        const float y = float(i % 32);
        m.push_back({Vec3f(x, y, 0), Vec3f(x + 1, y, 0), Vec3f(x, y + 1, 0)});
    }
    const auto t = KdTreeBuilder<float>{}.build(m);
    REQUIRE_FALSE(t.nodes[0].leaf);
    // The root cuts x in the empty gap [1, 10] between the two groups ...
    CHECK(t.nodes[0].axis == 0);
    CHECK(t.nodes[0].plane[0] >= 1.f);
    CHECK(t.nodes[0].plane[0] <= 10.f);
    // ... so the left subtree holds only the first group and the right only the second, and
    // every triangle is referenced at least once.
    std::vector<int> seen(m.size(), 0);
    const auto collect = [&](auto&& self, std::uint32_t node, bool left_side) -> void {
        const auto& nd = t.nodes[node];
        if (!nd.leaf) {
            self(self, nd.left, left_side);
            self(self, nd.right, left_side);
            return;
        }
        for (std::uint32_t k = nd.prim_begin; k < nd.prim_begin + nd.prim_count; ++k) {
            const std::uint32_t id = t.prims[k];
            CHECK((left_side ? id < 32u : id >= 32u));
            ++seen[id];
        }
    };
    collect(collect, t.nodes[0].left, true);
    collect(collect, t.nodes[0].right, false);
    for (int s : seen) CHECK(s >= 1);
}

TEST_CASE("errors: kd-tree cost constants out of range are rejected by name") {
    const Mesh<float> m{{Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)}};
    const auto build = [&](KdBuildOptions o) { return KdTreeBuilder<float>{o}.build(m); };
    KdBuildOptions o;
    CHECK_NOTHROW(build(o));
    o.intersection_cost = -1;
    CHECK_THROWS_WITH_AS(build(o), doctest::Contains("intersection_cost"), Error);
    o = {};
    o.traversal_cost = std::numeric_limits<double>::quiet_NaN();
    CHECK_THROWS_WITH_AS(build(o), doctest::Contains("traversal_cost"), Error);
    o = {};
    o.empty_bonus = 1.0;
    CHECK_THROWS_WITH_AS(build(o), doctest::Contains("empty_bonus"), Error);
    o = {};
    o.max_depth = -3;
    CHECK_THROWS_WITH_AS(build(o), doctest::Contains("max_depth"), Error);
}

TEST_CASE("agreement: Ivm, kd-tree and BIH, all layouts vs brute force") { check_intersector<Ivm<float>>(); }
TEST_CASE("agreement: MollerTrumbore, kd-tree and BIH, all layouts vs brute force") { check_intersector<MollerTrumbore<float>>(); }
TEST_CASE("agreement: Wald, kd-tree and BIH, all layouts vs brute force") { check_intersector<Wald<float>>(); }
TEST_CASE("agreement: Watertight, kd-tree and BIH, all layouts vs brute force") { check_intersector<Watertight<float>>(); }

// One test case per kind of wide BVH, so that the 10^6-ray run can be made for one alone.
TEST_CASE("agreement: wide BVH, 8 wide, every intersector vs brute force") { check_wide<WideBvh8>(); }
TEST_CASE("agreement: wide BVH, 4 wide, every intersector vs brute force") { check_wide<WideBvh4>(); }
TEST_CASE("agreement: wide BVH, 8 wide quantized boxes, every intersector vs brute force") { check_wide<QuantizedBvh8>(); }
TEST_CASE("agreement: wide BVH, 8 wide spatial splits, every intersector vs brute force") { check_wide<SpatialBvh8>(); }
TEST_CASE("agreement: wide BVH, 8 wide top-level spatial splits, every intersector vs brute force") {
    check_wide<TopSpatialBvh8>();
}
TEST_CASE("agreement: wide BVH, 8 wide compact subtrees, every intersector vs brute force") { check_wide<CompactBvh8>(); }

TEST_CASE("agreement: double precision kd-tree and BIH") {
    const Mesh<float> mf = make_torus_knot<float>();
    Mesh<double> m;
    for (const auto& t : mf) m.push_back({Vec3d(t[0]), Vec3d(t[1]), Vec3d(t[2])});
    const KdTree<double, MollerTrumbore<double>, CompactSubtrees<15>> kd(m);
    const Bih<double, MollerTrumbore<double>, HavranSubtrees<15>> bih(m);
    const BruteForce<MollerTrumbore<double>> bf(m);
    const auto rays = make_incoherent_rays<double>(m, 20000, 3);
    int errors = 0;
    for (const auto& r : rays) {
        StoreHit<double> a, b, c;
        const bool fa = kd.closest_hit(r, a), fb = bih.closest_hit(r, b), fc = bf.closest_hit(r, c);
        errors += fa != fc || fb != fc || (fc && (a.t != c.t || b.t != c.t));
    }
    CHECK(errors == 0);
}

namespace {

/// Ray i of the flat-grid stress tests (make_flat_grid: the unit square at z = 0): origins
/// in and around the square, half of them in its plane, a quarter of the directions in the
/// plane, some origins on grid lines, some rays along z.
Ray<float> flat_grid_ray(Pcg32& rng, int i) {
    Ray<float> r;
    r.origin = Vec3f(rng.uniform<float>() * 1.2f - 0.1f, rng.uniform<float>() * 1.2f - 0.1f,
                     i % 2 ? 0.f : rng.uniform<float>() - 0.5f);
    const float phi = 2 * pi<float> * rng.uniform<float>();
    r.direction = Vec3f(std::cos(phi), std::sin(phi), i % 4 == 1 ? 0.f : rng.uniform<float>() - 0.5f);
    if (i % 8 == 3) r.origin.x = float(rng.bounded(33)) / 32.f;  // on grid lines
    if (i % 8 == 5) r.direction = Vec3f(0, 0, rng.uniform<float>() < 0.5f ? 1.f : -1.f);
    return r;
}

}  // namespace

TEST_CASE("stress: flat geometry, rays in and along its plane") {
    const Mesh<float> m = make_flat_grid<float>(32);
    const KdTree<float, Watertight<float>, CompactSubtrees<31>> kd(m);
    const Bih<float, Watertight<float>, PointerLayout> bih(m);
    const BruteForce<Watertight<float>> bf(m);
    Pcg32 rng(9);
    int errors = 0;
    for (int i = 0; i < 20000; ++i) {
        const Ray<float> r = flat_grid_ray(rng, i);
        StoreHit<float> a, b, c;
        const bool fa = kd.closest_hit(r, a), fb = bih.closest_hit(r, b), fc = bf.closest_hit(r, c);
        errors += fa != fc || fb != fc || (fc && (a.t != c.t || b.t != c.t));
        errors += kd.any_hit(r) != fc;
    }
    CHECK(errors == 0);
}

TEST_CASE("stress: degenerate triangles, NaN and zero rays, far coordinates, empty scene") {
    Mesh<float> m = make_torus_knot<float>(40, 6);
    m.push_back({Vec3f(0), Vec3f(0), Vec3f(0)});                            // point
    m.push_back({Vec3f(0, 0, 0), Vec3f(1, 1, 1), Vec3f(2, 2, 2)});          // line
    m.push_back(m[5]);                                                      // duplicate
    m.push_back({Vec3f(NAN, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)});        // NaN vertex
    m.push_back({Vec3f(INFINITY, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)});   // infinite vertex
    const KdTree<float, Ivm<float>, CompactSubtrees<7>> kd(m);
    const Bih<float, Ivm<float>, CompactSubtrees<7>> bih(m);
    const std::uint32_t nan_id = std::uint32_t(m.size() - 2);
    Ray<float> r;
    r.origin = Vec3f(NAN, 0, 0);
    StoreHit<float> h;
    CHECK_FALSE(kd.closest_hit(r, h));
    CHECK_FALSE(bih.any_hit(r));
    r.origin = Vec3f(0, 0, 5);
    r.direction = Vec3f(0);
    CHECK_FALSE(kd.closest_hit(r, h));
    CHECK_FALSE(bih.closest_hit(r, h));
    const Vec3f target = (m[7][0] + m[7][1] + m[7][2]) / 3.f;
    r.direction = target - r.origin;
    CHECK(kd.closest_hit(r, h));
    CHECK(h.id != nan_id);
    CHECK(std::isfinite(h.t));

    // Far from the origin: the same scene moved by 10^4.
    Mesh<float> far = make_sphere<float>(20, 40, Vec3f(1e4f, -1e4f, 1e4f), 1.f);
    const KdTree<float, Watertight<float>, PointerLayout> kf(far);
    const BruteForce<Watertight<float>> bf(far);
    int errors = 0;
    for (const auto& ray : make_incoherent_rays<float>(far, 5000, 4)) {
        StoreHit<float> a, b;
        const bool fa = kf.closest_hit(ray, a), fb = bf.closest_hit(ray, b);
        errors += fa != fb || (fb && a.t != b.t);
    }
    CHECK(errors == 0);

    const Mesh<float> none;
    const KdTree<float, Wald<float>, CompactSubtrees<31>> e1(none);
    const Bih<float, Wald<float>, HavranSubtrees<7>> e2(none);
    r.origin = Vec3f(0);
    CHECK_FALSE(e1.closest_hit(r, h));
    CHECK_FALSE(e2.any_hit(r));
}

namespace {

/// Rays aimed at triangle centroids, with tmax (or tmin) NaN: the trees must report what brute
/// force reports (no hit), for every intersector (IVM leaves turned NaN into +inf).
template <class P>
void check_nan_interval() {
    const Mesh<float> m = make_torus_knot<float>(40, 6);
    const BruteForce<P> bf(m);
    const KdTree<float, P, CompactSubtrees<7>> kd(m);
    const Bih<float, P, PointerLayout> bih(m);
    int trees_hit = 0, brute_hit = 0, aimed = 0;
    for (std::size_t i = 0; i < m.size(); i += 7) {
        for (const bool nan_tmax : {true, false}) {
            Ray<float> r;
            r.origin = Vec3f(0.1f, 0.2f, 9.0f);
            r.direction = (m[i][0] + m[i][1] + m[i][2]) / 3.f - r.origin;
            (nan_tmax ? r.tmax : r.tmin) = std::numeric_limits<float>::quiet_NaN();
            StoreHit<float> a, b, c;
            brute_hit += bf.closest_hit(r, a);
            trees_hit += kd.closest_hit(r, b) + bih.closest_hit(r, c) + kd.any_hit(r) + bih.any_hit(r);
            ++aimed;
        }
    }
    INFO(type_label<P>());
    CHECK(aimed > 100);
    CHECK(brute_hit == 0);
    CHECK(trees_hit == 0);
}

}  // namespace

TEST_CASE("stress: rays with tmax or tmin NaN hit nothing in the trees, as in brute force") {
    check_nan_interval<Ivm<float>>();
    check_nan_interval<MollerTrumbore<float>>();
    check_nan_interval<Wald<float>>();
    check_nan_interval<Watertight<float>>();
}

namespace {

template <class L>
LayoutStats encode_stats(const BuiltTree<float>& t) {
    std::vector<std::array<std::uint32_t, 2>> groups(t.nodes.size(), {0u, 1u});
    std::vector<KdNode<float>> out;
    return L::encode(t, std::span<const std::array<std::uint32_t, 2>>(groups), out);
}

template <std::uint32_t K>
void check_memory(const BuiltTree<float>& t, const std::string& name) {
    const LayoutStats h = encode_stats<HavranSubtrees<K>>(t), c = encode_stats<CompactSubtrees<K>>(t);
    const double saving = 1.0 - double(c.node_bytes()) / double(h.node_bytes());
    INFO(name << " K=" << K << " havran " << h.node_bytes() << " B, compact " << c.node_bytes() << " B, saving "
              << saving);
    // Accounting is consistent.
    CHECK(h.slots == h.split_nodes + h.leaf_nodes + h.pointer_nodes + h.wasted_slots);
    CHECK(c.slots == c.split_nodes + c.leaf_nodes + c.pointer_nodes + c.wasted_slots);
    CHECK(h.leaf_nodes == t.leaf_count());
    CHECK(c.leaf_nodes == t.leaf_count());
    CHECK(c.node_bytes() <= h.node_bytes());
    // Szécsi 2009, Fig. 4.6: 20% less memory, 47% at 31-node subtrees (glint checks >= 20% at K >= 7,
    // >= 40% at K = 31).
    if (K >= 7) CHECK(saving >= 0.20);
    if (K == 31) CHECK(saving >= 0.40);
}

}  // namespace

TEST_CASE("memory: CompactSubtrees vs HavranSubtrees (Szécsi 2009, Fig. 4.6)") {
    for (const Scene& sc : scenes()) {
        const BuiltTree<float> t = KdTreeBuilder<float>{}.build(sc.mesh);
        const LayoutStats p = encode_stats<PointerLayout>(t);
        CHECK(p.wasted_slots == 0);
        CHECK(p.slots == t.nodes.size());
        CHECK(p.node_bytes() == 8 * t.nodes.size());
        const LayoutStats h3 = encode_stats<HavranSubtrees<3>>(t);
        CHECK(h3.slots == 3 * t.nodes.size());  // K = 3: a subtree per node, as node-and-pointers
        check_memory<3>(t, sc.name);
        check_memory<7>(t, sc.name);
        check_memory<15>(t, sc.name);
        check_memory<31>(t, sc.name);
        check_memory<63>(t, sc.name);
        const BuiltTree<float> b = BihBuilder<float>{}.build(sc.mesh);
        check_memory<7>(b, sc.name + " bih");
        check_memory<31>(b, sc.name + " bih");
    }
}

// ---------------------------------------------------------------------------------------
// The wide BVH (bvh_builder.hpp, wide_bvh.hpp, mesh_bvh.hpp). Its agreement with brute
// force runs with the other trees above (check_intersector: every intersector, 8 and 4 wide).

namespace {

/// Boxes of a mesh's triangles, as MeshBvh makes them.
std::vector<AABB<float>> triangle_boxes(const Mesh<float>& m) {
    std::vector<AABB<float>> boxes(m.size());
    for (std::size_t i = 0; i < m.size(); ++i)
        for (const auto& p : m[i]) boxes[i].extend(p);
    return boxes;
}

/// Closest hit through WideBvh::intersect with a user leaf callable (one Triangle per
/// primitive): the traversal API a user with their own primitives calls.
template <int N, WideBoxes B, WideNodeLayout L>
bool user_leaf_closest(const WideBvh<N, B, L>& bvh, const std::vector<Triangle<MollerTrumbore<float>>>& tris,
                       Ray<float> r, StoreHit<float>& hit) {
    return bvh.template intersect<false>(r, [&](std::uint32_t first, std::uint32_t count) {
        bool found = false;
        for (std::uint32_t k = first; k < first + count; ++k) {
            TriangleHit<float> h;
            if (tris[bvh.prims()[k]].intersect(r, h)) {
                r.tmax = h.t;
                hit.t = h.t;
                hit.id = bvh.prims()[k];
                found = true;
            }
        }
        return found;
    });
}

/// The SAH cost of a built wide tree per ray entering its root, from its nodes: C_N per wide
/// node and C_I per started leaf block, each weighted by its box's area.
template <int N>
double wide_tree_cost(const WideBvh<N>& t, const BvhBuildOptions& opt) {
    AABB<float> root;
    double cost = 0;
    for (std::size_t n = 0; n < t.nodes().size(); ++n)
        for (int i = 0; i < N; ++i) {
            const std::uint32_t c = t.nodes()[n].child[i];
            if (c == 0xffffffffu) continue;
            AABB<float> box;
            for (int a = 0; a < 3; ++a) {
                box.lo[a] = t.nodes()[n].bounds[2 * a][i];
                box.hi[a] = t.nodes()[n].bounds[2 * a + 1][i];
            }
            if (n == 0) root.extend(box);
            const double blocks = opt.blocks(detail::wide_leaf_count(c));
            cost += double(box.surface_area()) * (detail::wide_is_leaf(c) ? opt.intersection_cost * blocks : opt.wide_node_cost);
        }
    return cost / double(root.surface_area()) + opt.wide_node_cost;
}

/// The same cost for the simpler collapse glint used before (and Embree's BVH-N builders
/// use): a wide node opens the inner child of largest area until it has N children or only
/// binary leaves. Not divided by the root's area.
template <int N>
double area_collapse_cost(const BinaryBvh& bin, std::uint32_t slot, const BvhBuildOptions& opt) {
    std::vector<std::uint32_t> kids{slot + 1, bin.nodes[slot].right};
    for (;;) {
        auto open = kids.end();
        for (auto k = kids.begin(); k != kids.end(); ++k)
            if (!bin.nodes[*k].leaf() && (open == kids.end() || bin.nodes[*k].box.surface_area() > bin.nodes[*open].box.surface_area()))
                open = k;
        if (kids.size() == std::size_t(N) || open == kids.end()) break;
        const std::uint32_t s = *open;
        *open = s + 1;
        kids.push_back(bin.nodes[s].right);
    }
    double cost = opt.wide_node_cost * double(bin.nodes[slot].box.surface_area());
    for (std::uint32_t k : kids) {
        const BinaryBvhNode& c = bin.nodes[k];
        cost += c.leaf() ? opt.intersection_cost * double(opt.blocks(c.count)) * c.box.surface_area()
                         : area_collapse_cost<N>(bin, k, opt);
    }
    return cost;
}

/// The wide tree's leaves, sorted, tile prims() (each reference in exactly one leaf), and
/// hold at most max_leaf each.
template <int N>
bool leaves_tile(const WideBvh<N>& t, const BvhBuildOptions& opt) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves;
    for (const auto& n : t.nodes())
        for (std::uint32_t c : n.child)
            if (c != 0xffffffffu && detail::wide_is_leaf(c)) leaves.emplace_back(detail::wide_leaf_first(c), detail::wide_leaf_count(c));
    std::sort(leaves.begin(), leaves.end());
    std::uint32_t next = 0;
    for (const auto& [first, count] : leaves) {
        if (first != next || count == 0 || count > opt.max_leaf) return false;
        next = first + count;
    }
    return next == t.prims().size();
}

/// Every wide node has 2 ... N children (a one-leaf tree's root: 1).
template <int N>
bool nodes_full(const WideBvh<N>& t) {
    for (const auto& n : t.nodes()) {
        const auto k = std::count_if(n.child, n.child + N, [](std::uint32_t c) { return c != 0xffffffffu; });
        if (k < (t.nodes().size() == 1 && t.stats().leaves == 1 ? 1 : 2)) return false;
    }
    return true;
}

/// The least SAH cost of a collapse of `bin`, by trying, for every wide node, every set of
/// at most N binary subtrees that cuts it (exponential: small trees only); an oracle for
/// the dynamic programme, with the same costs (C_N per wide node, C_I per started block).
template <int N>
struct BruteCollapse {
    const BinaryBvh& bin;
    const BvhBuildOptions& opt;
    double area(std::uint32_t s) const { return double(bin.nodes[s].box.surface_area()); }
    std::vector<std::vector<std::uint32_t>> cuts(std::uint32_t s, int m) const {
        std::vector<std::vector<std::uint32_t>> all{{s}};
        if (bin.nodes[s].leaf() || m < 2) return all;
        for (const auto& l : cuts(s + 1, m - 1))
            for (const auto& r : cuts(bin.nodes[s].right, m - int(l.size()))) {
                all.push_back(l);
                all.back().insert(all.back().end(), r.begin(), r.end());
            }
        return all;
    }
    double as_leaf(std::uint32_t s) const {
        const BinaryBvhNode& b = bin.nodes[s];
        if (!b.leaf() && b.count > opt.max_leaf) return infinity<double>;
        return opt.intersection_cost * double(opt.blocks(b.count)) * area(s);
    }
    double as_node(std::uint32_t s) {
        if (const auto known = memo.find(s); known != memo.end()) return known->second;
        double best = infinity<double>;
        for (const auto& cut : cuts(s, N)) {
            if (cut.size() < 2) continue;
            double c = 0;
            for (std::uint32_t k : cut) c += bin.nodes[k].leaf() ? as_leaf(k) : std::min(as_leaf(k), as_node(k));
            best = std::min(best, c);
        }
        return memo[s] = best + opt.wide_node_cost * area(s);
    }
    std::map<std::uint32_t, double> memo;  // as_node, per binary subtree
};

/// The tree's queries with every kernel this CPU runs (core/isa.hpp) give the same floats.
template <int N, WideBoxes B>
void check_portable_and_user_leaf(const Scene& sc) {
    WideBvh<N, B> bvh(triangle_boxes(sc.mesh));
    std::vector<WideBvh<N, B>> others;  // every other kernel the build has (none with AVX2 flags)
    for (Isa isa : all_isas)
        if (isa_supported(isa) && isa != bvh.isa()) others.push_back(bvh), others.back().set_isa(isa);
    std::vector<Triangle<MollerTrumbore<float>>> tris;
    for (const auto& t : sc.mesh) tris.emplace_back(t[0], t[1], t[2]);
    const BruteForce<MollerTrumbore<float>> bf(sc.mesh);
    std::size_t differ = 0;
    Tally tally;
    for (std::size_t i = 0; i < sc.rays.size(); ++i) {
        const Ray<float>& r = sc.rays[i];
        StoreHit<float> a, b, ref;
        const bool fa = user_leaf_closest(bvh, tris, r, a);
        for (const auto& other : others) {  // SIMD and portable: the same floats
            b = StoreHit<float>{};
            const bool fb = user_leaf_closest(other, tris, r, b);
            differ += fa != fb || a.t != b.t || a.id != b.id;
        }
        // Against brute force (whose batch kernel may round differently from the scalar
        // test), by the agreement rules at the top of this file.
        const bool fr = bf.closest_hit(r, ref);
        compare(sc, i, a, fa, ref, fr, tally);
    }
    INFO(sc.name << " width " << N << " " << type_label<WideBvh<N, B>>() << " kernels " << std::string(isa_name(bvh.isa())) << " rays " << tally.rays << " hits " << tally.hits << " edges " << tally.edges
                 << " (generic " << tally.generic_edges << ") errors " << tally.errors);
    CHECK(differ == 0);
    CHECK(tally.errors == 0);
    CHECK(tally.generic_edges * 1000 <= tally.generic_rays);
    CHECK(tally.hits > tally.rays / 10);
}

}  // namespace

TEST_CASE("wide BVH: SIMD and portable box tests give the same hits; a user's leaf callable") {
    for (const Scene& sc : scenes()) {
        check_portable_and_user_leaf<8, WideBoxes::floats>(sc);
        check_portable_and_user_leaf<4, WideBoxes::floats>(sc);
        check_portable_and_user_leaf<8, WideBoxes::quantized>(sc);
        check_portable_and_user_leaf<4, WideBoxes::quantized>(sc);
    }
}

namespace {
/// A MeshBvh's closest and any hits with every kernel this CPU runs: the same floats.
template <class Bvh>
void check_kernels(const Scene& sc) {
    Bvh best(std::span<const TriangleVertices<float>>(sc.mesh));
    std::size_t differ = 0, kernels = 0;
    for (Isa isa : all_isas) {
        if (!isa_supported(isa) || isa == best.isa()) continue;
        Bvh other = best;
        other.set_isa(isa);
        ++kernels;
        for (const Ray<float>& r : sc.rays) {
            StoreHit<float> a, b;
            const bool fa = best.closest_hit(r, a), fb = other.closest_hit(r, b);
            differ += fa != fb || a.t != b.t || a.u != b.u || a.v != b.v || a.id != b.id;
            differ += best.any_hit(r) != other.any_hit(r);
        }
    }
    // The counted queries answer as the plain ones, and count what they test.
    WideBvhCounters closest_counts, any_counts;
    for (const Ray<float>& r : sc.rays) {
        StoreHit<float> a, b;
        differ += best.closest_hit(r, a) != best.closest_hit(r, b, closest_counts) || a.t != b.t || a.id != b.id;
        differ += best.any_hit(r) != best.any_hit(r, any_counts);
    }
    INFO(sc.name << " " << type_label<Bvh>() << " best kernels " << std::string(isa_name(best.isa())));
    // Without AVX2 flags: every kernel up to the best this CPU runs (portable = 0, sse2, avx2, avx512).
    if (GLINT_X86) CHECK(kernels == (compiled_isa >= Isa::avx2 ? 0u : unsigned(best_isa())));
    CHECK(differ == 0);
    CHECK(closest_counts.nodes >= sc.rays.size() / 2);  // most rays enter the root
    CHECK(any_counts.nodes > 0);
    CHECK(any_counts.leaves <= closest_counts.leaves);  // any hit stops at the first leaf that hits
    CHECK(any_counts.records <= closest_counts.records);
}
}  // namespace

TEST_CASE("MeshBvh: every kernel this CPU runs gives the same hits as the one chosen at construction") {
    CHECK(isa_supported(compiled_isa));  // a build with AVX2 or AVX-512 flags has only those kernels
    CHECK(isa_supported(Isa::portable) == (compiled_isa < Isa::avx2));
    if (compiled_isa >= Isa::avx2) CHECK(best_isa() == compiled_isa);
    CHECK(isa_supported(best_isa()));
    for (const Scene& sc : scenes()) {
        check_kernels<MeshBvh<MollerTrumbore<float>, 8>>(sc);
        check_kernels<MeshBvh<MollerTrumbore<float>, 4>>(sc);
        check_kernels<MeshBvh<Watertight<float>, 8, WideBoxes::quantized>>(sc);
    }
    MeshBvh<MollerTrumbore<float>, 8> bvh(std::span<const TriangleVertices<float>>(scenes().front().mesh));
    for (Isa isa : all_isas)
        if (!isa_supported(isa)) CHECK_THROWS_AS(bvh.set_isa(isa), Error);
}

TEST_CASE("wide BVH: quantized child boxes contain the float boxes, extreme ranges included") {
    Pcg32 rng(7);
    auto u = [&] { return rng.uniform<float>(); };
    std::size_t planes = 0, tight = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        // Node scales from 1e-30 to 1e30, offsets up to 1e6 node sizes, flat and point children.
        const float size = std::pow(10.0f, 60 * u() - 30), offset = size * std::pow(10.0f, 6 * u()) * (u() - 0.5f);
        WideBvhNode<8> f{};
        const int k = 1 + int(rng.bounded(8));
        for (int i = 0; i < 8; ++i) {
            f.child[i] = i;
            for (int a = 0; a < 3; ++a) {
                float lo = offset + size * u(), hi = lo + size * u() * (u() < 0.2f ? 0.0f : 1.0f);
                if (i >= k) lo = infinity<float>, hi = -infinity<float>;
                f.bounds[2 * a][i] = lo;
                f.bounds[2 * a + 1][i] = hi;
            }
        }
        const WideBvhQNode<8> q = detail::wide_quantize(f);
        REQUIRE(q.count == k);
        for (int a = 0; a < 3; ++a) {
            const float s = detail::wide_scale(q.exp[a]);
            // Looseness allowed: one step plus the rounding of the decoded plane (one ulp of
            // the largest decoded magnitude), twice (a loose box costs speed, not hits).
            const float big = std::abs(q.origin[a]) + 256 * s, ulp = std::nextafter(big, infinity<float>) - big;
            for (int i = 0; i < k; ++i) {
                const float lo = detail::wide_plane(q.origin[a], q.q[2 * a][i], s);
                const float hi = detail::wide_plane(q.origin[a], q.q[2 * a + 1][i], s);
                CHECK(lo <= f.bounds[2 * a][i]);
                CHECK(hi >= f.bounds[2 * a + 1][i]);
                ++planes;
                tight += f.bounds[2 * a][i] - lo <= 2 * (s + ulp) && hi - f.bounds[2 * a + 1][i] <= 2 * (s + ulp);
            }
        }
    }
    CHECK(tight == planes);
}

TEST_CASE("wide BVH: the tree does not depend on the thread count") {
    const Mesh<float> m = make_torus_knot<float>(400, 32);  // 25600 triangles: several parallel subtrees
    const auto boxes = triangle_boxes(m);
    const WideBvh<8> one(boxes, {.threads = 1}), two(boxes, {.threads = 2}), four(boxes, {.threads = 4});
    for (const WideBvh<8>* other : {&two, &four}) {
        REQUIRE(other->nodes().size() == one.nodes().size());
        CHECK(other->prims() == one.prims());
        CHECK(std::memcmp(other->nodes().data(), one.nodes().data(), one.nodes().size() * sizeof(WideBvhNode<8>)) == 0);
    }
    CHECK(one.stats().nodes > 100);
}

TEST_CASE("wide BVH: a host's executor runs the build's parallel splits; the tree is the one-thread tree") {
    const Mesh<float> m = make_torus_knot<float>(400, 32);
    const auto boxes = triangle_boxes(m);
    std::atomic<int> calls{0}, tasks{0};
    // Tasks one after another, last first; and each task on a std::thread of the host's.
    const Executor serial = [&](int n, const std::function<void(int)>& task) {
        ++calls;
        for (int i = n - 1; i >= 0; --i) ++tasks, task(i);
    };
    const Executor threaded = [&](int n, const std::function<void(int)>& task) {
        ++calls;
        std::vector<std::thread> pool;
        for (int i = 0; i < n; ++i) pool.emplace_back([&, i] { ++tasks, task(i); });
        for (auto& t : pool) t.join();
    };
    for (const bool spatial : {false, true}) {
        const WideBvh<8> one(boxes, {.threads = 1, .spatial_splits = spatial});
        for (const Executor* e : {&serial, &threaded}) {
            calls = 0, tasks = 0;
            const WideBvh<8> t(boxes, {.threads = 1, .executor = *e, .spatial_splits = spatial});
            INFO("spatial splits " << spatial << ", executor " << (e == &serial ? "serial" : "threaded") << ": " << calls << " calls");
            CHECK(calls > 2);  // the knot's large nodes went through it
            CHECK(tasks == 2 * calls);
            REQUIRE(t.nodes().size() == one.nodes().size());
            CHECK(t.prims() == one.prims());
            CHECK(std::memcmp(t.nodes().data(), one.nodes().data(), one.nodes().size() * sizeof(WideBvhNode<8>)) == 0);
        }
    }
}

template <int N>
void check_collapse(const Mesh<float>& mesh, const std::string& name, const std::vector<Ray<float>>& rays) {
    const auto boxes = triangle_boxes(mesh);
    std::vector<Triangle<MollerTrumbore<float>>> tris;
    for (const auto& t : mesh) tris.emplace_back(t[0], t[1], t[2]);
    const WideBvh<N> reference(boxes);
    for (const float c_n : {0.25f, 1.0f, 4.0f}) {
        const BvhBuildOptions opt{.wide_node_cost = c_n};
        const WideBvh<N> t(boxes, opt);
        const BinaryBvh bin = build_binary_bvh(std::span<const AABB<float>>(boxes), opt);
        const double cost = wide_tree_cost(t, opt);
        const double by_area = area_collapse_cost<N>(bin, 0, opt) / bin.nodes[0].box.surface_area();
        INFO(name << " width " << N << " C_N " << c_n << ": cost " << cost << " (collapse's own figure "
                  << t.stats().sah_cost << "), opening by area " << by_area << ", nodes " << t.stats().nodes);
        CHECK(std::abs(cost - t.stats().sah_cost) <= 1e-4 * cost);  // what was built is what was solved
        CHECK(cost <= by_area * (1 + 1e-6));
        CHECK(leaves_tile(t, opt));
        // Another collapse of the same binary tree: the same closest hits.
        std::size_t differ = 0;
        for (const Ray<float>& r : rays) {
            StoreHit<float> a, b;
            const bool fa = user_leaf_closest(t, tris, r, a);
            const bool fb = user_leaf_closest(reference, tris, r, b);
            differ += fa != fb || a.t != b.t;
        }
        CHECK(differ == 0);
    }
}

TEST_CASE("wide BVH: the collapse's SAH cost is what it solved, never above opening children by area; leaves tile the primitives") {
    for (const Scene& sc : scenes()) {
        const std::vector<Ray<float>> rays(sc.rays.begin(), sc.rays.begin() + std::min<std::size_t>(sc.rays.size(), 4000));
        check_collapse<8>(sc.mesh, sc.name, rays);
        check_collapse<4>(sc.mesh, sc.name, rays);
    }
    // On a mesh where the two differ: the solved collapse is cheaper.
    const Mesh<float> knot = make_torus_knot<float>(400, 32);
    const auto boxes = triangle_boxes(knot);
    const BvhBuildOptions opt{};
    const BinaryBvh bin = build_binary_bvh(std::span<const AABB<float>>(boxes), opt);
    const double by_area = area_collapse_cost<8>(bin, 0, opt) / bin.nodes[0].box.surface_area();
    const WideBvh<8> t(boxes, opt);
    INFO("knot, 25600 triangles: cost " << t.stats().sah_cost << ", opening by area " << by_area);
    CHECK(t.stats().sah_cost * 1.01 < by_area);
    // Scaled by 2^40 (exact in float): the same tree and cost. By 2^100, where box areas
    // overflow float (and the triangle tests' products would too), the collapse, which sums
    // areas in double, still gives leaves that tile the primitives and a finite cost.
    auto scaled = [&](int e) {
        Mesh<float> m = knot;
        for (auto& tri : m)
            for (auto& p : tri) p *= std::ldexp(1.0f, e);
        return WideBvh<8>(triangle_boxes(m), opt);
    };
    const WideBvh<8> big = scaled(40), huge = scaled(100);
    REQUIRE(big.nodes().size() == t.nodes().size());
    CHECK(big.prims() == t.prims());
    bool same_children = true;
    for (std::size_t n = 0; n < t.nodes().size(); ++n)
        for (int i = 0; i < 8; ++i) same_children &= big.nodes()[n].child[i] == t.nodes()[n].child[i];
    CHECK(same_children);
    CHECK(std::abs(big.stats().sah_cost - t.stats().sah_cost) <= 1e-5f * t.stats().sah_cost);
    CHECK(leaves_tile(huge, opt));
    CHECK(std::isfinite(huge.stats().sah_cost));
    CHECK(huge.stats().sah_cost >= opt.wide_node_cost);
}

TEST_CASE("wide BVH: the collapse is the cheapest one, by exhaustive search on small trees") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    int compared = 0;
    for (int trial = 0; trial < 400; ++trial) {
        Mesh<float> m;  // small random triangles, one in five a sliver of no area
        for (std::uint32_t i = 0, n = 5 + rng() % 60; i < n; ++i) {
            const Vec3f p(u(rng), u(rng), u(rng));
            const float e = 0.3f * u(rng) * u(rng);
            m.push_back({p, p + Vec3f(e * u(rng), e * u(rng), 0), p + Vec3f(0, e * u(rng), e * u(rng))});
            if (rng() % 5 == 0) m.back() = {p, p, p + Vec3f(e, 0, 0)};
        }
        const float c_n[] = {0, 0.3f, 1, 4};
        const BvhBuildOptions opt{.intersection_cost = rng() % 2 ? 1.0f : 0.3f, .leaf_block = std::uint32_t(1 + rng() % 8),
                                  .max_leaf = std::uint32_t(1 + rng() % 16), .wide_node_cost = c_n[rng() % 4]};
        const auto boxes = triangle_boxes(m);
        const BinaryBvh bin = build_binary_bvh(std::span<const AABB<float>>(boxes), opt);
        if (bin.nodes[0].leaf()) continue;
        auto check = [&]<int N>() {
            const WideBvh<N> t(boxes, opt);
            const double brute = BruteCollapse<N>{bin, opt, {}}.as_node(0) / double(bin.nodes[0].box.surface_area());
            INFO("trial " << trial << " width " << N << " triangles " << m.size() << ": collapse " << t.stats().sah_cost
                          << ", exhaustive " << brute);
            CHECK(std::abs(t.stats().sah_cost - brute) <= 1e-5 * brute);
            CHECK(nodes_full(t));
            CHECK(leaves_tile(t, opt));
        };
        check.template operator()<4>();
        check.template operator()<8>();
        ++compared;
    }
    CHECK(compared > 300);
}

TEST_CASE("wide BVH: boxes of no area (points, segments on a line) give full, shallow trees") {
    // 65536 copies of one point: 4096 leaves of 16, which 585 nodes of 8 (the fewest
    // possible, (4096 - 1) / 7 rounded up) hold in 4 levels above the leaves.
    const std::vector<AABB<float>> points(1 << 16, AABB<float>{Vec3f(1, 2, 3), Vec3f(1, 2, 3)});
    const WideBvh<8> p(points);
    CHECK(p.stats().leaves == 4096);
    CHECK(p.stats().nodes == 585);
    CHECK(p.stats().depth == 5);
    CHECK(nodes_full(p));
    // Collinear segments (every box a line): every node holds at least two children.
    std::vector<AABB<float>> segments(16000);
    for (std::size_t i = 0; i < segments.size(); ++i)
        segments[i] = AABB<float>{Vec3f(float(i), 0, 0), Vec3f(float(i) + 0.5f, 0, 0)};
    const WideBvh<8> s8(segments);
    const WideBvh<4> s4(segments);
    CHECK(nodes_full(s8));
    CHECK(nodes_full(s4));
    CHECK(leaves_tile(s8, BvhBuildOptions{}));
    INFO("segments: 8 wide depth " << s8.stats().depth << " nodes " << s8.stats().nodes << ", 4 wide depth "
                                   << s4.stats().depth << " nodes " << s4.stats().nodes);
    CHECK(s8.stats().nodes * 7 < s8.stats().leaves * 2);  // nodes hold 4.5 children or more on average
}

TEST_CASE("wide BVH: spatial splits stay within the reference budget, the tree does not depend on the thread count") {
    const Mesh<float> knot = make_torus_knot<float>(400, 32);  // 25600 triangles: several parallel subtrees
    const auto boxes = triangle_boxes(knot);
    const auto clip = [&](std::uint32_t j, int axis, const AABB<float>& region) {
        return clip_triangle(knot[j][0], knot[j][1], knot[j][2], axis, region);
    };
    BvhBuildOptions opt = BvhBuildOptions::full_spatial_splits();
    opt.threads = 1;
    const WideBvh<8> one(boxes, opt, clip);
    for (unsigned threads : {2u, 4u}) {
        opt.threads = threads;
        const WideBvh<8> other(boxes, opt, clip);
        REQUIRE(other.nodes().size() == one.nodes().size());
        CHECK(other.prims() == one.prims());
        CHECK(std::memcmp(other.nodes().data(), one.nodes().data(), one.nodes().size() * sizeof(WideBvhNode<8>)) == 0);
    }
    // Splits happen, within the budget; every triangle is referenced at least once.
    for (const float budget : {1.0f, 1.02f, 1.5f}) {
        opt.spatial_budget = budget;
        const WideBvh<8> t(boxes, opt, clip);
        const std::size_t refs = t.prims().size();
        CHECK(refs <= std::size_t(double(budget) * double(knot.size())));
        if (budget == 1.0f) CHECK(refs == knot.size());
        else CHECK(refs > knot.size());
        std::vector<char> seen(knot.size());
        for (std::uint32_t p : t.prims()) seen[p] = 1;
        CHECK(std::count(seen.begin(), seen.end(), 1) == std::ptrdiff_t(knot.size()));
    }
    // Without a clipper (NoClipper) spatial splits chop the boxes: splits happen within the
    // budget, and the tree finds the hits the tree without splits finds.
    const WideBvh<8> chopped(boxes, BvhBuildOptions::full_spatial_splits()), plain(boxes, {.spatial_splits = false});
    CHECK(chopped.prims().size() > knot.size());
    CHECK(chopped.prims().size() <= std::size_t(1.5 * double(knot.size())));
    std::vector<Triangle<MollerTrumbore<float>>> tris;
    for (const auto& t : knot) tris.emplace_back(t[0], t[1], t[2]);
    std::size_t generic = 0, differ = 0, hits = 0;
    for (const Ray<float>& r : ray_mix(knot, 20000, 11, generic)) {
        StoreHit<float> a, b;
        const bool fa = user_leaf_closest(chopped, tris, r, a), fb = user_leaf_closest(plain, tris, r, b);
        differ += fa != fb || a.t != b.t;  // the same exact tests: the same nearest t
        hits += fa;
    }
    CHECK(differ == 0);
    CHECK(hits > 2000);
    // A budget below 1 is refused.
    CHECK_THROWS_WITH_AS(WideBvh<8>(boxes, {.spatial_budget = 0.5f}, clip), doctest::Contains("spatial_budget"), Error);
    CHECK_THROWS_WITH_AS(WideBvh<8>(boxes, {.spatial_node_overlap = 2.0f}, clip), doctest::Contains("spatial_node_overlap"),
                         Error);
}

TEST_CASE("wide BVH: top-level spatial splits split within their budget, every thread count alike, the same hits") {
    const Mesh<float> knot = make_torus_knot<float>(400, 32);
    const auto boxes = triangle_boxes(knot);
    const auto clip = [&](std::uint32_t j, int axis, const AABB<float>& region) {
        return clip_triangle(knot[j][0], knot[j][1], knot[j][2], axis, region);
    };
    BvhBuildOptions opt = BvhBuildOptions::top_spatial_splits();
    opt.spatial_node_overlap = 0.0f;  // the knot's top nodes overlap little: try them all
    opt.threads = 1;
    const WideBvh<8> one(boxes, opt, clip), plain(boxes, {.spatial_splits = false}, clip);
    CHECK(one.prims().size() > knot.size());
    CHECK(one.prims().size() <= std::size_t(double(opt.spatial_budget) * double(knot.size())));
    for (unsigned threads : {2u, 4u}) {
        opt.threads = threads;
        const WideBvh<8> other(boxes, opt, clip);
        REQUIRE(other.nodes().size() == one.nodes().size());
        CHECK(other.prims() == one.prims());
    }
    std::vector<Triangle<MollerTrumbore<float>>> tris;
    for (const auto& t : knot) tris.emplace_back(t[0], t[1], t[2]);
    std::size_t generic = 0, differ = 0;
    for (const Ray<float>& r : ray_mix(knot, 20000, 11, generic)) {
        StoreHit<float> a, b;
        const bool fa = user_leaf_closest(one, tris, r, a), fb = user_leaf_closest(plain, tris, r, b);
        differ += fa != fb || a.t != b.t;
    }
    CHECK(differ == 0);
}

TEST_CASE("wide BVH: clip_triangle bounds the triangle's part in a slab, and nothing outside the region") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), w(0.0f, 1.0f);
    std::size_t points = 0, inside = 0, tighter = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const float s = std::pow(10.0f, float(trial % 7) - 3.0f);  // 10^-3 ... 10^3
        const Vec3f a(u(rng) * s, u(rng) * s, u(rng) * s), b(u(rng) * s, u(rng) * s, u(rng) * s),
            c(u(rng) * s, u(rng) * s, u(rng) * s);
        AABB<float> box;
        for (const Vec3f& p : {a, b, c}) box.extend(p);
        const int axis = trial % 3;
        AABB<float> region = box;  // a slab inside the triangle's box on `axis`
        float x0 = box.lo[axis] + w(rng) * (box.hi[axis] - box.lo[axis]);
        float x1 = box.lo[axis] + w(rng) * (box.hi[axis] - box.lo[axis]);
        region.lo[axis] = std::min(x0, x1);
        region.hi[axis] = std::max(x0, x1);
        const AABB<float> clipped = clip_triangle(a, b, c, axis, region);
        if (!clipped.empty()) {
            for (int k = 0; k < 3; ++k) {
                CHECK(clipped.lo[k] >= region.lo[k]);
                CHECK(clipped.hi[k] <= region.hi[k]);
            }
            tighter += clipped.surface_area() < 0.999f * region.surface_area();
        }
        for (int i = 0; i < 200; ++i) {  // points of the triangle in the slab (in double) lie in the clipped box
            double p = w(rng), q = w(rng);
            if (p + q > 1) p = 1 - p, q = 1 - q;
            const Vec3d x = Vec3d(a) + (Vec3d(b) - Vec3d(a)) * p + (Vec3d(c) - Vec3d(a)) * q;
            if (x[axis] < region.lo[axis] || x[axis] > region.hi[axis]) continue;
            ++points;
            bool in = true;
            for (int k = 0; k < 3; ++k) in = in && x[k] >= clipped.lo[k] && x[k] <= clipped.hi[k];
            inside += in;
        }
    }
    CHECK(points > 10000);
    CHECK(inside == points);
    CHECK(tighter > 1000);  // clipping the triangle, not its box, bounds it closer
}

TEST_CASE("wide BVH: sibling blocks place a node's inner children side by side, with the same hits") {
    const Scene& sc = scenes()[1];
    const auto boxes = triangle_boxes(sc.mesh);
    const WideBvh<8> depth(boxes), blocks(boxes, {.node_order = WideNodeOrder::sibling_blocks});
    REQUIRE(blocks.nodes().size() == depth.nodes().size());
    CHECK(blocks.prims() == depth.prims());
    std::size_t runs = 0;
    for (const auto& n : blocks.nodes()) {
        std::uint32_t next = 0;
        for (int i = 0; i < 8; ++i) {
            if (n.child[i] == 0xffffffffu || detail::wide_is_leaf(n.child[i])) continue;
            if (next != 0) CHECK(n.child[i] == next);  // consecutive
            next = n.child[i] + 1;
            ++runs;
        }
    }
    CHECK(runs + 1 == blocks.nodes().size());  // every node but the root is someone's child
    std::vector<Triangle<MollerTrumbore<float>>> tris;
    for (const auto& t : sc.mesh) tris.emplace_back(t[0], t[1], t[2]);
    std::size_t differ = 0;
    for (const Ray<float>& r : sc.rays) {
        StoreHit<float> a, b;
        const bool fa = user_leaf_closest(depth, tris, r, a);
        const bool fb = user_leaf_closest(blocks, tris, r, b);
        differ += fa != fb || a.t != b.t || a.id != b.id;
    }
    CHECK(differ == 0);
}

namespace {

/// Whether wide node `a` of tree `x` and node `b` of tree `y` hold the same boxes and leaves
/// and their inner children the same subtrees (the trees are equal up to node order).
template <int N, WideNodeLayout LX, WideNodeLayout LY>
bool same_subtree(const WideBvh<N, WideBoxes::floats, LX>& x, std::uint32_t a,
                  const WideBvh<N, WideBoxes::floats, LY>& y, std::uint32_t b) {
    const WideBvhNode<N>& p = x.nodes()[a];
    const WideBvhNode<N>& q = y.nodes()[b];
    if (std::memcmp(p.bounds, q.bounds, sizeof p.bounds) != 0) return false;
    for (int i = 0; i < N; ++i) {
        if (detail::wide_is_leaf(p.child[i]) != detail::wide_is_leaf(q.child[i])) return false;
        if (detail::wide_is_leaf(p.child[i]) ? p.child[i] != q.child[i] : !same_subtree(x, p.child[i], y, q.child[i]))
            return false;
    }
    return true;
}

/// The mean over nodes of the number of 4 KiB pages on the path from the root to the node
/// (node i at byte i * sizeof(node) of a page-aligned array): the pages a ray reaching it
/// has touched; 0 if some node's inner children are not side by side or precede it.
template <int N, WideNodeLayout L>
double pages_per_path(const WideBvh<N, WideBoxes::floats, L>& t) {
    const auto& nodes = t.nodes();
    std::vector<std::uint32_t> pages(nodes.size(), 1);  // distinct pages from the root, the node's included
    std::vector<std::uint32_t> parent(nodes.size(), 0);
    auto page = [&](std::uint32_t i) { return std::size_t(i) * sizeof(WideBvhNode<N>) / 4096; };
    double sum = 1;
    for (std::uint32_t p = 0; p < nodes.size(); ++p) {
        std::uint32_t next = 0;
        for (std::uint32_t c : nodes[p].child) {
            if (detail::wide_is_leaf(c)) continue;
            if ((next != 0 && c != next) || c <= p) return 0;
            next = c + 1;
            parent[c] = p;
            bool seen = false;  // is c's page on the path to p?
            for (std::uint32_t a = p;; a = parent[a]) {
                seen |= page(a) == page(c);
                if (a == 0) break;
            }
            pages[c] = pages[p] + (seen ? 0 : 1);
            sum += pages[c];
        }
    }
    return sum / double(nodes.size());
}

template <int N, std::uint32_t K>
void check_compact_subtrees(const Mesh<float>& mesh, const std::vector<Ray<float>>& rays, bool fewer_pages) {
    const auto boxes = triangle_boxes(mesh);
    const WideBvh<N> build(boxes), blocks(boxes, {.node_order = WideNodeOrder::sibling_blocks});
    const WideBvh<N, WideBoxes::floats, WideCompactSubtrees<K>> compact(boxes);
    REQUIRE(compact.nodes().size() == build.nodes().size());
    CHECK(compact.stats().node_bytes == build.stats().node_bytes);  // nothing padded
    CHECK(compact.prims() == build.prims());
    CHECK(same_subtree(build, 0, compact, 0));
    // Subtrees stored together: 4 wide (a page holds 9 sibling blocks) a path from the root
    // crosses fewer pages than in the collapse's sibling-block order (which descends depth
    // first from block to block); 8 wide a page holds only 2 blocks, and both orders put a
    // block and one child block on a page (docs/trees.md), so only the numbers are logged.
    const double compact_pages = pages_per_path(compact), block_pages = pages_per_path(blocks);
    INFO("width " << N << " K " << K << " nodes " << compact.nodes().size() << " pages per root path: compact "
                  << compact_pages << " sibling blocks " << block_pages);
    CHECK(compact_pages > 0);  // inner children side by side
    if (fewer_pages) CHECK(compact_pages < block_pages);
    std::vector<Triangle<MollerTrumbore<float>>> tris;
    for (const auto& t : mesh) tris.emplace_back(t[0], t[1], t[2]);
    std::size_t differ = 0;
    for (const Ray<float>& r : rays) {
        StoreHit<float> a, b;
        const bool fa = user_leaf_closest(build, tris, r, a);
        const bool fb = user_leaf_closest(compact, tris, r, b);
        differ += fa != fb || a.t != b.t || a.id != b.id;
    }
    CHECK(differ == 0);
}

/// A layout that does not return a permutation keeping the root.
struct SwapRootLayout {
    template <int N>
    static std::vector<std::uint32_t> arrange(std::span<const WideBvhNode<N>> nodes) {
        std::vector<std::uint32_t> at(nodes.size());
        for (std::size_t i = 0; i < at.size(); ++i) at[i] = std::uint32_t(at.size() - 1 - i);
        return at;
    }
};

}  // namespace

TEST_CASE("wide BVH: Szécsi 2009's compact subtrees on wide nodes: contiguous subtrees of at most K nodes, the same tree and hits") {
    const Mesh<float> m = make_torus_knot<float>(400, 32);  // 25600 triangles: subtrees below subtrees
    std::size_t generic = 0;
    const std::vector<Ray<float>> rays = ray_mix(m, 20000, 7, generic);
    check_compact_subtrees<8, 9>(m, rays, false);
    check_compact_subtrees<8, 18>(m, rays, false);
    check_compact_subtrees<4, 36>(m, rays, true);
    static_assert(WideNodeLayout<WideCompactSubtrees<18>> && WideNodeLayout<WideBuildOrder> && !WideNodeLayout<PointerLayout>);
    CHECK_THROWS_WITH_AS((WideBvh<8, WideBoxes::floats, SwapRootLayout>(triangle_boxes(scenes()[1].mesh))),
                         doctest::Contains("not a permutation"), Error);
}

TEST_CASE("wide BVH: the user's indexed mesh with a stride, hits report the user's triangle") {
    // Interleaved vertices (position, then a normal the BVH must skip), shared by triangles.
    const Mesh<float> soup = make_torus_knot<float>(60, 8);
    struct Vertex {
        float p[3];
        float n[3];
    };
    std::vector<Vertex> verts;
    std::vector<std::uint32_t> idx;
    for (std::size_t j = soup.size(); j-- > 0;) {  // reversed: user order differs from the soup's
        for (const auto& v : soup[j]) {
            idx.push_back(std::uint32_t(verts.size()));
            verts.push_back({{v.x, v.y, v.z}, {0, 0, 1}});
        }
    }
    const IndexedMesh<float> mesh{verts.data(), verts.size(), sizeof(Vertex), idx.data(), soup.size()};
    const MeshBvh<Watertight<float>> bvh(mesh);
    const BruteForce<Watertight<float>> bf(soup);
    int errors = 0, hits = 0;
    for (const auto& r : make_incoherent_rays<float>(soup, 5000, 7)) {
        StoreHit<float> a, b;
        const bool fa = bvh.closest_hit(r, a), fb = bf.closest_hit(r, b);
        hits += fb;
        errors += fa != fb || (fb && (a.t != b.t || soup.size() - 1 - a.id != b.id));
    }
    CHECK(errors == 0);
    CHECK(hits > 1000);
    idx[7] = std::uint32_t(verts.size());
    CHECK_THROWS_WITH_AS(MeshBvh<Watertight<float>>{mesh}, doctest::Contains("triangle 2 has vertex index"), Error);
    IndexedMesh<float> thin = mesh;
    thin.stride_bytes = 8;
    CHECK_THROWS_AS(MeshBvh<Watertight<float>>{thin}, Error);
    CHECK_THROWS_AS(WideBvh<8>(triangle_boxes(soup), BvhBuildOptions{.max_leaf = 17}), Error);
}

static_assert(std::is_same_v<MeshBvh<>, MeshBvh<MollerTrumbore<float>, 8, WideBoxes::floats, WideBuildOrder>>);

TEST_CASE("MeshBvh<>: a hit's geometric normal from the user's mesh, in its winding, by the hit's id") {
    Mesh<float> soup = make_torus_knot<float>(60, 8);
    soup.push_back({Vec3f(0), Vec3f(1, 0, 0), Vec3f(2, 0, 0)});  // degenerate: normal 0
    std::vector<std::uint32_t> idx;
    std::vector<Vec3f> verts;
    for (std::size_t j = soup.size(); j-- > 0;)  // reversed, and the winding flipped
        for (int k : {0, 2, 1}) {
            idx.push_back(std::uint32_t(verts.size()));
            verts.push_back(soup[j][std::size_t(k)]);
        }
    const IndexedMesh<float> mesh{verts.data(), verts.size(), sizeof(Vec3f), idx.data(), soup.size()};
    const MeshBvh<> a(soup);
    const MeshBvh<Watertight<float>, 4> b(mesh, BvhBuildOptions::full_spatial_splits());
    CHECK(geometric_normal(soup.back()) == Vec3f(0));
    CHECK(mesh.geometric_normal(0) == Vec3f(0));
    int hits = 0, bad = 0, compared = 0;
    for (const auto& r : make_incoherent_rays<float>(soup, 5000, 9)) {
        StoreHit<float> ha, hb;
        if (!a.closest_hit(r, ha)) continue;
        ++hits;
        const auto& t = soup[ha.id];
        const Vec3d e = glm::cross(Vec3d(t[1]) - Vec3d(t[0]), Vec3d(t[2]) - Vec3d(t[0]));
        const Vec3f n = geometric_normal(t);
        // Unit, along e1 x e2 (to float rounding), the hit point on its plane.
        bad += std::abs(glm::length(Vec3d(n)) - 1.0) > 1e-6 || glm::length(Vec3d(n) - e / glm::length(e)) > 1e-6 ||
               std::abs(glm::dot(Vec3d(r.at(ha.t)) - Vec3d(t[0]), Vec3d(n))) > 1e-4;
        // The other tree reports the user's index in the reversed mesh, whose winding is flipped.
        if (b.closest_hit(r, hb) && soup.size() - 1 - hb.id == ha.id) {
            ++compared;
            bad += mesh.geometric_normal(hb.id) != -n;
        }
    }
    CHECK(hits > 1000);
    CHECK(compared > hits * 9 / 10);
    CHECK(bad == 0);
}

TEST_CASE("wide BVH: NaN tmax, empty interval, NaN and zero rays, degenerate and flat scenes") {
    Mesh<float> m = make_torus_knot<float>(40, 6);
    m.push_back({Vec3f(0), Vec3f(0), Vec3f(0)});
    m.push_back({Vec3f(0, 0, 0), Vec3f(1, 1, 1), Vec3f(2, 2, 2)});
    m.push_back({Vec3f(NAN, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)});
    m.push_back({Vec3f(INFINITY, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)});
    const MeshBvh<MollerTrumbore<float>, 8> b8(m);
    const MeshBvh<Ivm<float>, 4> b4(m);
    const Vec3f target = (m[7][0] + m[7][1] + m[7][2]) / 3.f;
    Ray<float> r;
    r.origin = Vec3f(0, 0, 5);
    r.direction = target - r.origin;
    StoreHit<float> h;
    REQUIRE(b8.closest_hit(r, h));
    CHECK(b4.any_hit(r));
    for (float tmax : {NAN, 0.f, -1.f}) {  // NaN tmax, and intervals that hold nothing
        Ray<float> q = r;
        q.tmax = tmax;
        StoreHit<float> hq;
        CHECK_FALSE(b8.closest_hit(q, hq));
        CHECK_FALSE(b4.closest_hit(q, hq));
        CHECK_FALSE(b8.any_hit(q));
    }
    Ray<float> q = r;
    q.origin.x = NAN;
    CHECK_FALSE(b8.closest_hit(q, h));
    q = r;
    q.direction = Vec3f(0);
    CHECK_FALSE(b8.any_hit(q));
    // A flat grid with rays in and along its plane.
    const Mesh<float> flat = make_flat_grid<float>(32);
    const MeshBvh<Watertight<float>> fb(flat);
    const BruteForce<Watertight<float>> bf(flat);
    Pcg32 rng(11);
    int errors = 0;
    for (int i = 0; i < 20000; ++i) {
        const Ray<float> s = flat_grid_ray(rng, i);
        StoreHit<float> a, c;
        const bool fa = fb.closest_hit(s, a), fc = bf.closest_hit(s, c);
        errors += fa != fc || (fc && a.t != c.t) || fb.any_hit(s) != fc;
    }
    CHECK(errors == 0);
    const Mesh<float> none;
    const MeshBvh<Wald<float>> e(none);
    CHECK_FALSE(e.closest_hit(r, h));
    CHECK_FALSE(e.any_hit(r));
}

namespace {

/// A user's own primitive: a sphere, with the nearest root of |o + t d - c|^2 = r^2 in
/// (tmin, tmax) as its hit.
struct UserSphere {
    Vec3f c;
    float r;
    bool intersect(const Ray<float>& ray, float& t) const {
        const Vec3f oc = ray.origin - c;
        const float a = glm::dot(ray.direction, ray.direction), b = glm::dot(oc, ray.direction);
        const float disc = b * b - a * (glm::dot(oc, oc) - r * r);
        if (!(disc >= 0.0f)) return false;
        const float s = std::sqrt(disc);
        for (const float root : {(-b - s) / a, (-b + s) / a})
            if (root > ray.tmin && root < ray.tmax) {
                t = root;
                return true;
            }
        return false;
    }
};

}  // namespace

TEST_CASE("wide BVH: a user's own primitives (spheres) in the leaves through the leaf callable agree with brute force") {
    Pcg32 rng(7);
    std::vector<UserSphere> spheres(3000);
    std::vector<AABB<float>> boxes;
    for (UserSphere& s : spheres) {
        s.c = Vec3f(rng.uniform(), rng.uniform(), rng.uniform()) * 10.0f;
        s.r = 0.02f + 0.2f * rng.uniform();
        boxes.push_back(AABB<float>{s.c - Vec3f(s.r), s.c + Vec3f(s.r)});
    }
    const WideBvh<8> bvh(boxes);
    std::size_t rays = 0, hits = 0, wrong = 0, any_wrong = 0;
    for (; rays < 20000; ++rays) {
        Ray<float> ray;
        ray.origin = Vec3f(rng.uniform(), rng.uniform(), rng.uniform()) * 12.0f - Vec3f(1.0f);
        ray.direction = Vec3f(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0f - Vec3f(1.0f);
        ray.tmin = 0.0f;
        ray.tmax = rays % 2 ? 5.0f : infinity<float>;
        // Brute force: the nearest sphere (the first of equal t).
        float best_t = ray.tmax;
        std::uint32_t best = ~0u;
        for (std::uint32_t i = 0; i < spheres.size(); ++i) {
            float t;
            if (spheres[i].intersect(Ray<float>{ray.origin, ray.direction, ray.tmin, best_t}, t)) {
                best_t = t;
                best = i;
            }
        }
        // The tree: its leaf callable tests the leaf's spheres and lowers tmax to each hit.
        const auto leaf_for = [&spheres, &bvh](Ray<float>& q, std::uint32_t& found) {
            return [&spheres, &bvh, &q, &found](std::uint32_t first, std::uint32_t count) {
                bool any = false;
                for (std::uint32_t k = first; k < first + count; ++k) {
                    float t;
                    if (spheres[bvh.prims()[k]].intersect(q, t)) {
                        q.tmax = t;
                        found = bvh.prims()[k];
                        any = true;
                    }
                }
                return any;
            };
        };
        Ray<float> r = ray, shadow = ray;
        std::uint32_t found = ~0u, shadow_found = ~0u;
        const bool hit = bvh.intersect<false>(r, leaf_for(r, found));
        hits += best != ~0u;
        // The same t (the same sphere, or one whose root rounds to the same float).
        wrong += hit != (best != ~0u) || (hit && (r.tmax != best_t || found == ~0u));
        any_wrong += bvh.intersect<true>(shadow, leaf_for(shadow, shadow_found)) != (best != ~0u);
    }
    INFO("rays " << rays << " hits " << hits << " wrong " << wrong << " any-hit wrong " << any_wrong);
    CHECK(wrong == 0);
    CHECK(any_wrong == 0);
    CHECK(hits > rays / 10);
    CHECK(hits < rays);  // some rays miss: the test is not vacuous either way
}

// Concepts: a wrong type is reported where the template is named, not deep inside traversal.
// `Names<...>` is true exactly when the specialization is well-formed, i.e. every concept
// constraining its parameters is satisfied.
namespace {
struct NotALayout {};
struct OnlyClosestHit {  // an accelerator without any_hit
    using scalar_type = float;
    bool closest_hit(const Ray<float>&, StoreHit<float>&) const { return false; }
};
template <class T, class P, class L>
concept NamesKdTree = requires { typename KdTree<T, P, L>; };
template <class T, class P, class L>
concept NamesBih = requires { typename Bih<T, P, L>; };
template <class P>
concept NamesMeshBvh = requires { typename MeshBvh<P>; };
template <class P>
concept NamesBruteForce = requires { typename BruteForce<P>; };
}  // namespace

static_assert(NodeLayout<PointerLayout> && NodeLayout<CompactSubtrees<31>> && NodeLayout<HavranSubtrees<15>>);
static_assert(!NodeLayout<int> && !NodeLayout<NotALayout> && !NodeLayout<Ivm<float>>);
static_assert(TriangleIntersector<Ivm<float>> && TriangleIntersector<MollerTrumbore<double>> &&
              TriangleIntersector<Wald<float>> && TriangleIntersector<Watertight<float>>);
static_assert(!TriangleIntersector<int> && !TriangleIntersector<PointerLayout> && !TriangleIntersector<UserSphere>);
static_assert(RayAccelerator<KdTree<float, Ivm<float>, PointerLayout>> && RayAccelerator<Bih<float, Wald<float>, CompactSubtrees<15>>> &&
              RayAccelerator<MeshBvh<MollerTrumbore<float>>> && RayAccelerator<BruteForce<Watertight<float>>>);
static_assert(!RayAccelerator<OnlyClosestHit> && !RayAccelerator<PointerLayout> && !RayAccelerator<WideBvh<8>>);
static_assert(NamesKdTree<float, MollerTrumbore<float>, PointerLayout> && NamesBih<float, Ivm<float>, CompactSubtrees<31>>);
static_assert(!NamesKdTree<float, int, PointerLayout>);                 // not an intersector
static_assert(!NamesKdTree<float, Ivm<float>, int>);                    // not a layout
static_assert(!NamesKdTree<float, PointerLayout, Ivm<float>>);          // swapped
static_assert(!NamesKdTree<float, Ivm<double>, PointerLayout>);         // scalar types differ
static_assert(!NamesBih<float, MollerTrumbore<float>, NotALayout>);
static_assert(!NamesMeshBvh<int> && !NamesMeshBvh<Ivm<double>> && NamesMeshBvh<Wald<float>>);
static_assert(!NamesBruteForce<PointerLayout> && NamesBruteForce<Ivm<float>>);
static_assert(LeafTest<bool (*)(std::uint32_t, std::uint32_t)> && !LeafTest<int> && !LeafTest<void (*)(std::uint32_t)>);
