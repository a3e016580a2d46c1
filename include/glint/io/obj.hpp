// glint/io/obj.hpp: Wavefront OBJ/MTL loading through tinyobjloader.
//
// Needs tinyobjloader 2 (Debian libtinyobjloader-dev): link tinyobjloader::tinyobjloader.
// Polygons are triangulated as fans; every face gets the index of its material (faces
// without one get a default grey Lambertian material). From the MTL: Kd, Ks, Ns, Ke
// (emission), Ni (index of refraction) and illum. A missing or malformed file throws
// glint::Error naming the file and what is wrong.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <tiny_obj_loader.h>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

struct ObjMaterial {
    std::string name = "default";
    Rgb<float> kd{0.5f}, ks{0.0f}, ke{0.0f};
    float ns = 0.0f;   // Phong exponent
    float ni = 1.0f;   // index of refraction
    int illum = 2;
};

struct ObjMesh {
    std::vector<TriangleVertices<float>> triangles;
    std::vector<std::uint32_t> material;  // per triangle, index into materials
    std::vector<ObjMaterial> materials;
};

/// Loads `path` (and the MTL files it names, looked up next to it).
inline ObjMesh load_obj(const std::string& path) {
    tinyobj::ObjReaderConfig config;
    config.triangulate = false;  // we fan-triangulate ourselves, keeping material per face
    const auto slash = path.find_last_of('/');
    config.mtl_search_path = slash == std::string::npos ? "./" : path.substr(0, slash + 1);
    tinyobj::ObjReader reader;
    if (!reader.ParseFromFile(path, config))
        throw Error("load_obj(" + path + "): " + (reader.Error().empty() ? "cannot read the file" : reader.Error()));
    const auto& attrib = reader.GetAttrib();
    ObjMesh mesh;
    for (const auto& m : reader.GetMaterials()) {
        ObjMaterial om;
        om.name = m.name;
        om.kd = Rgb<float>(m.diffuse[0], m.diffuse[1], m.diffuse[2]);
        om.ks = Rgb<float>(m.specular[0], m.specular[1], m.specular[2]);
        om.ke = Rgb<float>(m.emission[0], m.emission[1], m.emission[2]);
        om.ns = m.shininess;
        om.ni = m.ior;
        om.illum = m.illum;
        mesh.materials.push_back(om);
    }
    const auto default_material = static_cast<std::uint32_t>(mesh.materials.size());
    mesh.materials.push_back(ObjMaterial{});
    const std::size_t nv = attrib.vertices.size() / 3;
    for (const auto& shape : reader.GetShapes()) {
        std::size_t offset = 0;
        for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f) {
            const std::size_t count = shape.mesh.num_face_vertices[f];
            if (count < 3)
                throw Error("load_obj(" + path + "): shape '" + shape.name + "' face " + std::to_string(f) +
                            " has " + std::to_string(count) + " vertices, expected at least 3");
            auto vertex = [&](std::size_t k) {
                const int i = shape.mesh.indices[offset + k].vertex_index;
                if (i < 0 || std::size_t(i) >= nv)
                    throw Error("load_obj(" + path + "): shape '" + shape.name + "' face " + std::to_string(f) +
                                " refers to vertex " + std::to_string(i + 1) + " of " + std::to_string(nv));
                return Vec3f(attrib.vertices[3 * std::size_t(i)], attrib.vertices[3 * std::size_t(i) + 1],
                             attrib.vertices[3 * std::size_t(i) + 2]);
            };
            const int mid = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
            const std::uint32_t mat = mid >= 0 && std::size_t(mid) < default_material
                                          ? static_cast<std::uint32_t>(mid) : default_material;
            const Vec3f v0 = vertex(0);
            for (std::size_t k = 1; k + 1 < count; ++k) {
                mesh.triangles.push_back({v0, vertex(k), vertex(k + 1)});
                mesh.material.push_back(mat);
            }
            offset += count;
        }
    }
    if (mesh.triangles.empty()) throw Error("load_obj(" + path + "): no faces");
    for (const auto& t : mesh.triangles)
        for (const auto& p : t)
            if (!all_finite(p)) throw Error("load_obj(" + path + "): a vertex is not finite");
    return mesh;
}

}  // namespace glint
