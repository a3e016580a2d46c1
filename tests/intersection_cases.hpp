// Ray-triangle cases shared by tests/test_intersection.cpp and
// benchmarks/stress_intersection.cpp: random pairs, stress categories, a closed mesh, and
// the measurement of each policy against the extended-precision reference.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/random.hpp>
#include <glint/intersection/reference.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint::testing {

template <class T>
struct Case {
    Ray<T> ray;
    TriangleVertices<T> tri;
};

template <class T>
Vec3<T> random_in_box(Pcg32& rng, T half) {
    return Vec3<T>((rng.uniform<T>() * 2 - 1) * half, (rng.uniform<T>() * 2 - 1) * half,
                   (rng.uniform<T>() * 2 - 1) * half);
}

/// A ray from a random origin towards a point of the triangle's plane with barycentrics
/// in [-0.25, 1.25]^2: about half hit, many pass close to edges.
template <class T>
Ray<T> ray_towards(Pcg32& rng, const TriangleVertices<T>& t, const Vec3<T>& origin) {
    const T u = rng.uniform<T>() * T(1.5) - T(0.25), v = rng.uniform<T>() * T(1.5) - T(0.25);
    const Vec3<T> target = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
    return Ray<T>{origin, target - origin, T(0), infinity<T>};
}

/// Random triangles in [-1,1]^3 shifted by `offset`, rays from [-3,3]^3 + offset.
template <class T>
std::vector<Case<T>> random_cases(std::uint64_t seed, std::size_t n, T offset = 0) {
    Pcg32 rng(seed);
    std::vector<Case<T>> cases(n);
    for (auto& c : cases) {
        const Vec3<T> shift = safe_normalize(random_in_box<T>(rng, 1)) * offset;
        for (auto& p : c.tri) p = random_in_box<T>(rng, 1) + shift;
        c.ray = ray_towards(rng, c.tri, random_in_box<T>(rng, 3) + shift);
    }
    return cases;
}

/// Slivers: the third vertex at relative height 10^-1 ... 10^-6 above the opposite edge.
template <class T>
std::vector<Case<T>> sliver_cases(std::uint64_t seed, std::size_t n) {
    Pcg32 rng(seed);
    std::vector<Case<T>> cases(n);
    for (auto& c : cases) {
        const Vec3<T> a = random_in_box<T>(rng, 1), b = random_in_box<T>(rng, 1);
        const Vec3<T> side = safe_normalize(glm::cross(b - a, random_in_box<T>(rng, 1)));
        const T height = std::pow(T(10), -T(1) - T(5) * rng.uniform<T>()) * glm::length(b - a);
        c.tri = {a, b, a + (b - a) * rng.uniform<T>() + side * height};
        c.ray = ray_towards(rng, c.tri, random_in_box<T>(rng, 3));
    }
    return cases;
}

/// Triangles whose plane passes through the world origin (the IVM's singular case).
template <class T>
std::vector<Case<T>> origin_plane_cases(std::uint64_t seed, std::size_t n) {
    Pcg32 rng(seed);
    std::vector<Case<T>> cases(n);
    for (auto& c : cases) {
        const Vec3<T> p = random_in_box<T>(rng, 1), q = random_in_box<T>(rng, 1);
        // Vertices are combinations of two vectors: the plane span(p, q) contains 0.
        const T s[6] = {rng.uniform<T>() * 2 - 1, rng.uniform<T>() * 2 - 1, rng.uniform<T>() * 2 - 1,
                        rng.uniform<T>() * 2 - 1, rng.uniform<T>() * 2 - 1, rng.uniform<T>() * 2 - 1};
        c.tri = {p * s[0] + q * s[1], p * s[2] + q * s[3], p * s[4] + q * s[5]};
        c.ray = ray_towards(rng, c.tri, random_in_box<T>(rng, 3));
    }
    return cases;
}

/// Zero-area triangles: a point, a repeated vertex, three exactly collinear points (small
/// integer coordinates, so collinearity is exact). Every ray must miss.
template <class T>
std::vector<Case<T>> zero_area_cases(std::uint64_t seed, std::size_t n) {
    Pcg32 rng(seed);
    auto lattice = [&] {
        return Vec3<T>(T(rng.bounded(16)) - 8, T(rng.bounded(16)) - 8, T(rng.bounded(16)) - 8);
    };
    std::vector<Case<T>> cases(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3<T> a = lattice(), e = lattice();
        auto& tri = cases[i].tri;
        switch (i % 3) {
            case 0: tri = {a, a, a}; break;
            case 1: tri = {a, a + e, a}; break;
            default: tri = {a, a + e, a + e * T(2)}; break;
        }
        cases[i].ray = ray_towards(rng, tri, random_in_box<T>(rng, 3));
    }
    return cases;
}

/// Rays parallel to the triangle's plane z = 1: half exactly in the plane, half beside it.
/// Every ray must miss.
template <class T>
std::vector<Case<T>> parallel_cases(std::uint64_t seed, std::size_t n) {
    Pcg32 rng(seed);
    std::vector<Case<T>> cases(n);
    for (std::size_t i = 0; i < n; ++i) {
        const T z = (i % 2) ? T(1) : T(1) + (rng.uniform<T>() - T(0.5));
        cases[i].tri = {Vec3<T>(0, 0, 1), Vec3<T>(2, 0, 1), Vec3<T>(0, 2, 1)};
        cases[i].ray = Ray<T>{{rng.uniform<T>() * 6 - 3, rng.uniform<T>() * 6 - 3, z},
                              {rng.uniform<T>() - T(0.5), rng.uniform<T>() - T(0.5), 0}};
    }
    return cases;
}

/// Rays with NaN or infinite origin, direction or interval, and a zero direction, against
/// an ordinary triangle. Every ray must miss.
template <class T>
std::vector<Case<T>> nonfinite_cases() {
    const T nan = std::numeric_limits<T>::quiet_NaN(), inf = infinity<T>;
    const TriangleVertices<T> tri{Vec3<T>(-1, -1, 1), Vec3<T>(1, -1, 1), Vec3<T>(0, 1, 1)};
    const Ray<T> rays[] = {
        {{nan, 0, 0}, {0, 0, 1}}, {{0, 0, 0}, {0, nan, 1}}, {{0, 0, 0}, {0, 0, nan}},
        {{inf, 0, 0}, {0, 0, 1}}, {{0, 0, -inf}, {0, 0, 1}}, {{0, 0, 0}, {0, 0, inf}},
        {{0, 0, 0}, {inf, inf, inf}}, {{0, 0, 0}, {0, 0, 0}}, {{0, 0, 0}, {0, 0, 1}, nan, inf},
        {{0, 0, 0}, {0, 0, 1}, 0, nan}};
    std::vector<Case<T>> cases;
    for (const auto& r : rays) cases.push_back({r, tri});
    return cases;
}

/// How a policy's decisions compare with the reference on a set of cases.
struct Agreement {
    std::size_t pairs = 0, undefined = 0, reference_hits = 0;  // undefined: must miss
    std::size_t false_miss = 0, false_hit = 0;            // any disagreement
    std::size_t false_miss_far = 0, false_hit_far = 0;    // disagreements outside the band
    double max_disagreement_ulps = 0;                     // widest edge distance of a disagreement
    double max_t_ulps = 0;                                // |t - t_ref| / t_unit when both hit
    bool nan_out = false;                                 // NaN in a reported hit
};

/// Tests every case with Triangle<P> (the world-space API: IVM gets its own frame). Where
/// the reference is undefined (zero area, ray in or parallel to the plane, non-finite
/// input) the only right answer is a miss, and any hit counts as a far false hit.
template <class P>
Agreement measure_agreement(const std::vector<Case<typename P::scalar_type>>& cases, double band) {
    using T = typename P::scalar_type;
    Agreement a;
    for (const auto& c : cases) {
        const ReferenceHit ref = reference_intersect(c.ray, c.tri[0], c.tri[1], c.tri[2]);
        ++a.pairs;
        TriangleHit<T> h;
        const bool hit = Triangle<P>(c.tri[0], c.tri[1], c.tri[2]).intersect(c.ray, h);
        if (hit && !(std::isfinite(h.t) && std::isfinite(h.u) && std::isfinite(h.v))) a.nan_out = true;
        if (!ref.defined) {
            ++a.undefined;
            if (hit) ++a.false_hit, ++a.false_hit_far;
            continue;
        }
        a.reference_hits += ref.hit;
        if (hit != ref.hit) {
            (ref.hit ? a.false_miss : a.false_hit)++;
            if (ref.edge_ulps > band) (ref.hit ? a.false_miss_far : a.false_hit_far)++;
            a.max_disagreement_ulps = std::max(a.max_disagreement_ulps, ref.edge_ulps);
        } else if (hit) {
            const double err = std::abs(double(h.t) - double(ref.t)) / ref.t_unit;
            a.max_t_ulps = std::max(a.max_t_ulps, err);
        }
    }
    return a;
}

/// A closed, convex triangle mesh: an icosahedron subdivided `levels` times and projected
/// onto a sphere of radius `radius` around `centre`, with shared (indexed) vertices so
/// neighbouring triangles see bit-identical edge endpoints.
template <class T>
struct ClosedMesh {
    std::vector<Vec3<T>> vertices;
    std::vector<std::array<std::uint32_t, 3>> faces;
    Vec3<T> centre;
    T radius;

    TriangleVertices<T> triangle(std::size_t f) const {
        return {vertices[faces[f][0]], vertices[faces[f][1]], vertices[faces[f][2]]};
    }
    std::vector<TriangleVertices<T>> triangles() const {
        std::vector<TriangleVertices<T>> out;
        for (std::size_t f = 0; f < faces.size(); ++f) out.push_back(triangle(f));
        return out;
    }
    /// Unique undirected edges.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges() const {
        std::map<std::pair<std::uint32_t, std::uint32_t>, int> seen;
        for (const auto& f : faces)
            for (int i = 0; i < 3; ++i) seen[std::minmax(f[i], f[(i + 1) % 3])] = 1;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
        for (const auto& [e, one] : seen) out.push_back(e);
        return out;
    }
};

template <class T>
ClosedMesh<T> icosphere(int levels, Vec3<T> centre, T radius) {
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                            {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    std::vector<std::array<std::uint32_t, 3>> f = {
        {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
        {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
        {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
        auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            v.push_back((v[a] + v[b]) * 0.5);
            return mid[key] = static_cast<std::uint32_t>(v.size() - 1);
        };
        std::vector<std::array<std::uint32_t, 3>> next;
        for (const auto& t : f) {
            const std::uint32_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]),
                                ca = midpoint(t[2], t[0]);
            next.push_back({t[0], ab, ca});
            next.push_back({t[1], bc, ab});
            next.push_back({t[2], ca, bc});
            next.push_back({ab, bc, ca});
        }
        f = std::move(next);
    }
    ClosedMesh<T> m;
    m.centre = centre;
    m.radius = radius;
    for (const auto& p : v) m.vertices.push_back(Vec3<T>(glm::normalize(p) * double(radius) + Vec3d(centre)));
    m.faces = std::move(f);
    return m;
}

/// Rays aimed exactly at the mesh's vertices and at points on its edges (endpoints
/// interpolated and rounded to T, so they lie on the edge up to rounding): from random
/// interior points outwards, and from outside inwards. Every one of them must hit the
/// closed mesh; a miss is a leak.
template <class T>
std::vector<Ray<T>> edge_vertex_rays(const ClosedMesh<T>& m, std::uint64_t seed, int per_feature) {
    Pcg32 rng(seed);
    std::vector<Vec3<T>> targets = m.vertices;
    for (const auto& [a, b] : m.edges())
        for (int i = 0; i < per_feature; ++i) {
            const T s = rng.uniform<T>();
            targets.push_back(m.vertices[a] + (m.vertices[b] - m.vertices[a]) * s);
        }
    std::vector<Ray<T>> rays;
    for (const Vec3<T>& target : targets) {
        for (int i = 0; i < per_feature; ++i) {
            const Vec3<T> inside = m.centre + random_in_box<T>(rng, m.radius * T(0.5));
            rays.push_back(Ray<T>{inside, target - inside, T(0), infinity<T>});
            const Vec3<T> dir = safe_normalize(target - m.centre + random_in_box<T>(rng, m.radius * T(0.3)));
            const Vec3<T> outside = target + dir * (m.radius * T(2));
            rays.push_back(Ray<T>{outside, target - outside, T(0), infinity<T>});
        }
    }
    return rays;
}

/// Fraction of rays that find no triangle of the closed mesh (all triangles in one
/// TriangleStore block, the way a tree leaf or brute force holds them).
template <class P>
double leak_rate(const ClosedMesh<typename P::scalar_type>& m,
                 const std::vector<Ray<typename P::scalar_type>>& rays, std::size_t& leaks) {
    using T = typename P::scalar_type;
    TriangleStore<P> store;
    const auto tris = m.triangles();
    std::vector<std::uint32_t> ids(tris.size());
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::uint32_t>(i);
    const auto block = store.add_block(tris, ids);
    leaks = 0;
    for (const auto& r : rays) {
        StoreHit<T> h;
        if (!store.closest_hit(block, r, h)) ++leaks;
    }
    return rays.empty() ? 0.0 : double(leaks) / double(rays.size());
}

/// The closed-mesh leak test: icospheres at the origin, off-centre and 10^4 away, rays
/// aimed at their edges and vertices. Returns the number of leaks; `rays` gets the total.
template <class P>
std::size_t closed_mesh_leaks(std::size_t& rays) {
    using T = typename P::scalar_type;
    std::size_t leaks_total = 0;
    rays = 0;
    for (const Vec3<T> centre : {Vec3<T>(0), Vec3<T>(T(0.3), T(-0.7), T(0.1)),
                                 Vec3<T>(T(1e4), T(-2e4), T(5e3))}) {
        const auto mesh = icosphere<T>(2, centre, T(1));
        const auto shot = edge_vertex_rays(mesh, 3, 4);
        std::size_t leaks = 0;
        leak_rate<P>(mesh, shot, leaks);
        rays += shot.size();
        leaks_total += leaks;
    }
    return leaks_total;
}

}  // namespace glint::testing
