// refract_cones: a glass object in a procedural environment, rendered with the hierarchical
// ray engine (000 chapter 6, Fig. 6.8): every pass traces one generation of rays through
// RayTileEngine (tiles of rays, one enclosing cone each, triangle spheres tested against
// the cones), refracts (or, under total internal reflection, reflects) the rays that hit,
// and lets the rays that leave the object read the environment map and drop out.
//
//   refract_cones [--mesh FILE.obj] [--size N] [--tile N] [--passes N] [--out PREFIX]
//
// Without --mesh the object is a glass torus knot (14400 triangles). With --mesh (for
// example ../shared/scenes/bunny.obj) the OBJ's faces are used, y up. Writes PREFIX.png
// (tone-mapped, stb_image_write) and PREFIX.exr (linear, OpenEXR); PREFIX defaults to
// "refract_cones".
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <string>
#include <vector>

#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <OpenEXR/ImfRgbaFile.h>

#include <glint/cones/glass.hpp>
#include <glint/cones/ray_tiles.hpp>
#include <glint/core/error.hpp>
#include <glint/intersection/ivm.hpp>
#include "tree_scenes.hpp"

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

/// Triangles of an OBJ file (polygons fan-triangulated by tinyobjloader).
Mesh<float> load_obj(const std::string& path) {
    tinyobj::ObjReader reader;
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    if (!reader.ParseFromFile(path, config))
        throw Error("refract_cones: cannot read OBJ '" + path + "': " + reader.Error());
    const auto& v = reader.GetAttrib().vertices;
    Mesh<float> mesh;
    for (const auto& shape : reader.GetShapes()) {
        const auto& idx = shape.mesh.indices;
        for (std::size_t i = 0; i + 2 < idx.size(); i += 3) {
            TriangleVertices<float> t;
            for (int k = 0; k < 3; ++k) {
                const int j = idx[i + k].vertex_index;
                t[k] = Vec3f(v[3 * j], v[3 * j + 1], v[3 * j + 2]);
            }
            mesh.push_back(t);
        }
    }
    if (mesh.empty()) throw Error("refract_cones: OBJ '" + path + "' has no faces");
    return mesh;
}

/// Procedural environment map: a sky with a sun above the horizon, a checkered floor
/// below it (fading with distance), in coordinates with `up` as the zenith.
Vec3f environment(const Vec3f& d, const Vec3f& up, const Vec3f& b1, const Vec3f& b2) {
    const float z = glm::dot(d, up);
    if (z >= 0.0f) {
        const Vec3f sun_dir = glm::normalize(0.5f * b1 - 0.3f * b2 + 0.6f * up);
        const float sun = std::pow(std::max(0.0f, glm::dot(d, sun_dir)), 400.0f) * 40.0f;
        const float t = std::pow(1.0f - z, 3.0f);
        return (1.0f - t) * Vec3f(0.15f, 0.35f, 0.8f) + t * Vec3f(0.9f, 0.9f, 0.95f) + Vec3f(sun, sun * 0.9f, sun * 0.7f);
    }
    // Floor plane one unit below: the point where the direction meets it.
    const float s = 1.0f / std::max(-z, 1e-4f);
    const float u = glm::dot(d, b1) * s, v = glm::dot(d, b2) * s;
    const bool odd = (int(std::floor(u)) + int(std::floor(v))) & 1;
    const float fade = std::exp(-0.02f * s);
    const Vec3f tile = odd ? Vec3f(0.85f, 0.2f, 0.1f) : Vec3f(0.9f, 0.85f, 0.7f);
    return fade * tile + (1.0f - fade) * Vec3f(0.6f, 0.6f, 0.65f);
}

}  // namespace

int main(int argc, char** argv) try {
    std::string mesh_path, out = "refract_cones";
    int size = 512, tile = 16, passes = 8;
    cli::App app("refract_cones: refracted rays through a glass object, the ray-tile hierarchy against brute force");
    cli::text(app, "--mesh", mesh_path, "FILE.obj: the glass object (default: a torus knot)");
    cli::text(app, "--out", out, "PREFIX of the images written");
    cli::number(app, "--size", size, 1, 8192, "image width and height");
    cli::number(app, "--tile", tile, 1, 8192, "tile edge in pixels");
    cli::number(app, "--passes", passes, 1, 1 << 16, "passes");
    if (!cli::parse(app, argc, argv)) return 0;

    // The glass object and its frame: z up for the knot, y up for OBJ files.
    const Mesh<float> mesh = mesh_path.empty() ? make_torus_knot<float>(300, 24) : load_obj(mesh_path);
    const std::span<const TriangleVertices<float>> tris(mesh);
    const Vec3f up = mesh_path.empty() ? Vec3f(0, 0, 1) : Vec3f(0, 1, 0);
    Vec3f b1, b2;
    orthonormal_basis(up, b1, b2);
    const AABB<float> box = mesh_bounds(tris);
    const Vec3f centre = box.center();
    const float radius = 0.5f * glm::length(box.extent());

    // Camera rays (row-major, one per pixel centre), looking at the object from above.
    const Vec3f eye = centre + 2.6f * radius * glm::normalize(-0.9f * b2 + 0.3f * b1 + 0.7f * up);
    const Vec3f fwd = glm::normalize(centre - eye), right = glm::normalize(glm::cross(fwd, up));
    const Vec3f cam_up = glm::cross(right, fwd);
    const float half_fov = 0.45f;
    std::vector<Ray<float>> rays(std::size_t(size) * size);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float sx = (2.0f * (x + 0.5f) / size - 1.0f) * half_fov, sy = (1.0f - 2.0f * (y + 0.5f) / size) * half_fov;
            rays[std::size_t(y) * size + x] = Ray<float>{eye, glm::normalize(fwd + sx * right + sy * cam_up)};
        }

    // The engine (triangle records + spheres) and the glass: index 1.5, a faint green tint
    // per segment inside. The pass loop calls `shade` for every active ray after each pass:
    // a hit refracts (GlassShader), a miss reads the environment and ends the path.
    const RayTileEngine<Ivm<float>> engine(tris);
    const GlassShader<float> glass(tris, 1.5f, 1e-4f * glm::length(box.extent()));
    std::vector<Vec3f> image(rays.size(), Vec3f(0)), throughput(rays.size(), Vec3f(1));
    auto shade = [&](std::size_t i, Ray<float>& r, const StoreHit<float>& h, bool found) {
        if (!found) {
            image[i] = throughput[i] * environment(glm::normalize(r.direction), up, b1, b2);
            return false;
        }
        throughput[i] *= Vec3f(0.97f, 0.99f, 0.97f);
        return glass(i, r, h, found);
    };
    TileWorkspace<float> ws;
    const auto t0 = std::chrono::steady_clock::now();
    const PassStats s = engine.trace_passes(std::span<Ray<float>>(rays), TileGrid(size, size, tile), passes, shade, ws);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // Paths still inside after the last pass: the environment in their current direction.
    for (std::size_t i = 0; i < rays.size(); ++i)
        if (ws.active[i]) image[i] = throughput[i] * environment(glm::normalize(rays[i].direction), up, b1, b2);

    std::printf("%zu triangles, %d x %d rays in %d x %d tiles: %d passes, %llu ray segments, %.1f ray-triangle tests "
                "per segment (brute force: %zu), %.3f s\n",
                mesh.size(), size, size, tile, tile, s.passes, (unsigned long long)s.rays, s.tests_per_ray(),
                mesh.size(), seconds);

    // Linear EXR and tone-mapped (Reinhard, gamma 2.2) PNG.
    std::vector<Imf::Rgba> exr(image.size());
    std::vector<unsigned char> png(image.size() * 3);
    for (std::size_t i = 0; i < image.size(); ++i) {
        exr[i] = Imf::Rgba(image[i].x, image[i].y, image[i].z, 1.0f);
        for (int c = 0; c < 3; ++c) {
            const float v = image[i][c] / (1.0f + image[i][c]);
            png[3 * i + c] = static_cast<unsigned char>(std::clamp(std::pow(v * 1.6f, 1.0f / 2.2f), 0.0f, 1.0f) * 255.0f + 0.5f);
        }
    }
    Imf::RgbaOutputFile file((out + ".exr").c_str(), size, size, Imf::WRITE_RGBA);
    file.setFrameBuffer(exr.data(), 1, std::size_t(size));
    file.writePixels(size);
    if (!stbi_write_png((out + ".png").c_str(), size, size, 3, png.data(), size * 3))
        throw Error("refract_cones: cannot write " + out + ".png");
    std::printf("wrote %s.png and %s.exr\n", out.c_str(), out.c_str());
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
}
