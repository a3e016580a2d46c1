// trace_your_mesh: ray tracing a mesh that lives in your own arrays with glint's fastest
// tree, the 8-wide BVH (trees/mesh_bvh.hpp).
//
//   trace_your_mesh [out.ppm]
//
// 1. Your mesh: here a wavy terrain of shared vertices (position and normal interleaved, as
//    a renderer keeps them) and 32-bit triangle indices. glint reads both in place.
// 2. The tree: MeshBvh over an IndexedMesh view (pointer, count, byte stride, indices).
// 3. Camera rays for the closest hit, a shadow ray toward the sun for any hit, Lambert shading.
// 4. The image, written as a binary PPM.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/trees/mesh_bvh.hpp>

using namespace glint;

struct Vertex {  // the application's own vertex layout
    float position[3];
    float normal[3];
};

int main(int argc, char** argv) {
    // 1. A 200 x 200 grid of vertices over [-1, 1]^2, heights from a few waves.
    const int n = 200;
    std::vector<Vertex> vertices;
    std::vector<std::uint32_t> indices;
    auto height = [](float x, float y) { return 0.15f * std::sin(6 * x) * std::cos(5 * y) + 0.05f * std::sin(17 * x * y); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const float x = 2.0f * i / (n - 1) - 1, y = 2.0f * j / (n - 1) - 1, e = 1e-3f;
            const Vec3f normal = glm::normalize(Vec3f(height(x - e, y) - height(x + e, y), height(x, y - e) - height(x, y + e), 2 * e));
            vertices.push_back({{x, y, height(x, y)}, {normal.x, normal.y, normal.z}});
        }
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const std::uint32_t a = std::uint32_t(j * n + i), b = a + 1, c = a + std::uint32_t(n), d = c + 1;
            indices.insert(indices.end(), {a, b, d, a, d, c});
        }

    // 2. The tree, built on two threads straight from those arrays.
    const IndexedMesh<float> mesh{vertices.data(), vertices.size(), sizeof(Vertex), indices.data(), indices.size() / 3};
    const auto build_start = std::chrono::steady_clock::now();
    const MeshBvh<MollerTrumbore<float>, 8> bvh(mesh, {.threads = 2});
    const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
    std::printf("%zu triangles, built in %.3f s\n", mesh.triangle_count, build_s);

    // 3. A pinhole camera above the terrain, the sun low in the sky.
    const int width = 512, height_px = 384;
    const Vec3f eye(0, -2.2f, 1.4f), target(0, 0, 0), up(0, 0, 1);
    const Vec3f forward = glm::normalize(target - eye), right = glm::normalize(glm::cross(forward, up));
    const Vec3f cam_up = glm::cross(right, forward), sun = glm::normalize(Vec3f(-1, 0.5f, 0.6f));
    std::vector<unsigned char> pixels;
    for (int py = 0; py < height_px; ++py)
        for (int px = 0; px < width; ++px) {
            const float sx = (2 * (px + 0.5f) / width - 1) * 0.6f * width / height_px, sy = (1 - 2 * (py + 0.5f) / height_px) * 0.6f;
            Ray<float> ray;
            ray.origin = eye;
            ray.direction = glm::normalize(forward + sx * right + sy * cam_up);
            StoreHit<float> hit;
            float shade = 0.15f + 0.1f * ray.direction.z;  // the sky
            if (bvh.closest_hit(ray, hit)) {
                // hit.id is an index into *your* triangles: interpolate your normals.
                const std::uint32_t* tri = &indices[3 * std::size_t(hit.id)];
                Vec3f normal(0);
                const float w[3] = {1 - hit.u - hit.v, hit.u, hit.v};
                for (int k = 0; k < 3; ++k) normal += w[k] * Vec3f(vertices[tri[k]].normal[0], vertices[tri[k]].normal[1], vertices[tri[k]].normal[2]);
                normal = glm::normalize(normal);
                Ray<float> shadow;
                shadow.origin = ray.at(hit.t) + 1e-4f * normal;
                shadow.direction = sun;
                const bool lit = !bvh.any_hit(shadow);
                shade = 0.08f + (lit ? 0.9f * std::max(0.0f, glm::dot(normal, sun)) : 0.0f);
            }
            const auto byte = static_cast<unsigned char>(255.0f * std::sqrt(std::min(1.0f, std::max(0.0f, shade))));
            pixels.insert(pixels.end(), {byte, byte, byte});
        }

    // 4. The image.
    const std::string path = argc > 1 ? argv[1] : "trace_your_mesh.ppm";
    std::ofstream out(path, std::ios::binary);
    out << "P6\n" << width << ' ' << height_px << "\n255\n";
    out.write(reinterpret_cast<const char*>(pixels.data()), std::streamsize(pixels.size()));
    if (!out) {
        std::fprintf(stderr, "trace_your_mesh: cannot write %s\n", path.c_str());
        return 1;
    }
    std::printf("wrote %s (%d x %d)\n", path.c_str(), width, height_px);
    return 0;
}
