// render_obj: an OBJ mesh through glint's tree into an EXR image, shaded by its geometric
// normals and lit by a point light with shadow rays: the pieces a renderer of your own
// starts from.
//
//   render_obj [mesh.obj] [out.exr] [size]     (default ../shared/scenes/bunny.obj; a sphere if absent)
//
// 1. Triangles: the OBJ's (io/obj.hpp) or a generated sphere, and a floor under them.
// 2. The tree: MeshBvh<> (trees/mesh_bvh.hpp), glint's fastest.
// 3. A camera framing the bounds (core/camera.hpp) and a point light above it.
// 4. Per pixel: the closest hit, its triangle's geometric normal, a shadow ray from an origin
//    offset past the hit point's rounding error (core/offset.hpp), Lambert's cosine over r^2.
// 5. The image as EXR (io/exr.hpp).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <glint/core/camera.hpp>
#include <glint/core/offset.hpp>
#include <glint/io/exr.hpp>
#include <glint/io/obj.hpp>
#include <glint/trees/mesh_bvh.hpp>

using namespace glint;

int main(int argc, char** argv) try {
    const std::string path = argc > 1 ? argv[1] : "../shared/scenes/bunny.obj", out = argc > 2 ? argv[2] : "render_obj.exr";
    const int size = argc > 3 ? std::stoi(argv[3]) : 512;

    // 1. Triangles (a unit sphere of 32 x 16 quads when there is no file), then a floor.
    std::vector<TriangleVertices<float>> tris;
    if (std::filesystem::exists(path)) tris = load_obj(path).triangles;
    auto at = [](int i, int j) {
        const float phi = 6.2831853f * float(i) / 32, theta = 3.1415927f * float(j) / 16;
        return Vec3f(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi));
    };
    for (int q = 0, sphere = tris.empty(); sphere && q < 32 * 16; ++q) {  // quad q, counter-clockwise from outside
        const int i = q % 32, k = q / 32;
        tris.push_back({at(i, k), at(i, k + 1), at(i + 1, k + 1)});
        tris.push_back({at(i, k), at(i + 1, k + 1), at(i + 1, k)});
    }
    AABB<float> box;
    for (const auto& t : tris)
        for (const Vec3f& p : t) box.extend(p);
    const Vec3f c = box.center();
    const float r = glm::length(box.extent()) * 0.5f, y = box.lo.y, f = 4 * r;
    tris.push_back({Vec3f(c.x - f, y, c.z - f), Vec3f(c.x - f, y, c.z + f), Vec3f(c.x + f, y, c.z + f)});
    tris.push_back({Vec3f(c.x - f, y, c.z - f), Vec3f(c.x + f, y, c.z + f), Vec3f(c.x + f, y, c.z - f)});

    // 2. The tree.
    const MeshBvh<> bvh(tris);

    // 3. Camera and light.
    const Camera<float> camera{c + Vec3f(0.0f, 0.3f, 1.0f) * (r * 2.6f), c, Vec3f(0, 1, 0), 0.7f};
    const Vec3f light = c + Vec3f(-1.0f, 2.0f, 1.5f) * r;
    const float intensity = 3 * r * r;  // radiant intensity, so that the top of the mesh gets about 1

    // 4. One ray per pixel centre; the sky grey.
    Image<Rgb<float>> image(size, size, Rgb<float>(0.05f));
    for (int py = 0; py < size; ++py)
        for (int px = 0; px < size; ++px) {
            const Ray<float> ray = camera.ray((float(px) + 0.5f) / float(size), (float(py) + 0.5f) / float(size), 1.0f);
            StoreHit<float> hit;
            if (!bvh.closest_hit(ray, hit)) continue;
            Vec3f n = geometric_normal(tris[hit.id]);  // hit.id: the index of your triangle
            if (glm::dot(n, ray.direction) > 0) n = -n;  // the side the camera sees
            const SurfacePoint<float> p = surface_point(tris[hit.id], hit.u, hit.v);
            const Vec3f to_light = light - p.x;
            const Vec3f o = offset_origin(p.x, p.err, n, to_light);
            const bool shadowed = bvh.any_hit(Ray<float>{o, light - o, 0.0f, 1.0f});  // t in (0, 1): up to the light
            const float cosine = std::max(0.0f, glm::dot(n, glm::normalize(to_light)));
            const float e = shadowed ? 0.0f : intensity * cosine / glm::dot(to_light, to_light);
            image.at(px, py) = Rgb<float>(0.8f * (0.03f + e));  // albedo 0.8, a little ambient light
        }

    // 5. The EXR.
    write_exr(out, image);
    std::printf("%zu triangles; wrote %s (%d x %d)\n", tris.size(), out.c_str(), size, size);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "render_obj: %s\n", e.what());
    return 1;
}
