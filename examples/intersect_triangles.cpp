// intersect_triangles: every ray-triangle policy of glint on the same rays.
//
// Reads top to bottom as a reference for using glint/intersection:
//   1. one triangle in world space with Triangle<P>;
//   2. a mesh in a TriangleStore (the structure-of-arrays blocks tree leaves use), shot
//      with a pinhole camera's rays, for each policy, compared with the watertight test.
#include <chrono>
#include <cstdio>
#include <vector>

#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/wald.hpp>
#include <glint/intersection/watertight.hpp>

using namespace glint;

// A closed test mesh: a torus of `rings` x `sides` quads, each split into two triangles.
std::vector<TriangleVertices<float>> make_torus(int rings, int sides, float R, float r) {
    auto point = [&](int i, int j) {
        const float u = 2 * pi<float> * float(i % rings) / float(rings);
        const float v = 2 * pi<float> * float(j % sides) / float(sides);
        return Vec3f((R + r * std::cos(v)) * std::cos(u), r * std::sin(v), (R + r * std::cos(v)) * std::sin(u));
    };
    std::vector<TriangleVertices<float>> tris;
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < sides; ++j) {
            tris.push_back({point(i, j), point(i + 1, j), point(i + 1, j + 1)});
            tris.push_back({point(i, j), point(i + 1, j + 1), point(i, j + 1)});
        }
    return tris;
}

struct Result {
    std::vector<std::uint32_t> ids;  // hit triangle per ray, or ~0u
    double seconds;
};

// Shoots every ray at the whole mesh (brute force over one store block).
template <class P>
Result shoot(const std::vector<TriangleVertices<float>>& tris, const std::vector<Ray<float>>& rays) {
    TriangleStore<P> store;
    std::vector<std::uint32_t> ids(tris.size());
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::uint32_t>(i);
    const auto block = store.add_block(tris, ids);

    Result result{std::vector<std::uint32_t>(rays.size(), ~0u), 0.0};
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < rays.size(); ++i) {
        StoreHit<float> hit;
        if (store.closest_hit(block, rays[i], hit)) result.ids[i] = hit.id;
    }
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

int main() {
    // 1. One triangle, one ray. Barycentrics (u, v) weight vertices 1 and 2.
    const Triangle<Ivm<float>> tri(Vec3f(0, 0, 5), Vec3f(4, 0, 5), Vec3f(0, 4, 5));
    TriangleHit<float> h;
    if (tri.intersect(Ray<float>{Vec3f(1, 1, 0), Vec3f(0, 0, 1)}, h))
        std::printf("single triangle: t = %g, u = %g, v = %g\n\n", h.t, h.u, h.v);

    // 2. A torus seen by a 128 x 128 pinhole camera.
    const auto mesh = make_torus(48, 24, 1.0f, 0.35f);
    std::vector<Ray<float>> rays;
    const int res = 128;
    const Vec3f eye(0, 2.5f, -3.5f), forward = glm::normalize(-eye);
    Vec3f right, up;
    orthonormal_basis(forward, right, up);
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            const float sx = (float(x) + 0.5f) / res * 2 - 1, sy = (float(y) + 0.5f) / res * 2 - 1;
            rays.push_back(Ray<float>{eye, forward + right * (0.45f * sx) + up * (0.45f * sy)});
        }

    const Result ref = shoot<Watertight<float>>(mesh, rays);
    const Result results[] = {shoot<Ivm<float>>(mesh, rays), shoot<MollerTrumbore<float>>(mesh, rays),
                              shoot<Wald<float>>(mesh, rays), ref};
    const char* names[] = {"Ivm", "MollerTrumbore", "Wald", "Watertight"};

    const double tests = double(rays.size()) * double(mesh.size());
    std::printf("%zu triangles, %zu rays (brute force, batch kernel)\n", mesh.size(), rays.size());
    {
        TriangleStore<Ivm<float>> ivm_store;
        std::vector<std::uint32_t> ids(mesh.size(), 0);
        ivm_store.add_block(mesh, ids);
        std::printf("the IVM store split the mesh into %zu frames (see ivm.hpp)\n", ivm_store.group_count());
    }
    std::printf("%-16s %8s %22s %12s\n", "policy", "hits", "differs from watertight", "ns/test");
    for (int p = 0; p < 4; ++p) {
        std::size_t hits = 0, differ = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            hits += results[p].ids[i] != ~0u;
            differ += results[p].ids[i] != ref.ids[i];
        }
        std::printf("%-16s %8zu %22zu %12.3f\n", names[p], hits, differ, results[p].seconds * 1e9 / tests);
    }
    std::printf("\n(timings from one run on a shared machine: see bench_intersection for medians)\n");
    return 0;
}
