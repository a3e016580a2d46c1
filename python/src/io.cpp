// glint.load_obj and glint.load_gltf: a mesh file as numpy arrays. glint's loaders give
// triangle soups (io/obj.hpp, io/gltf.hpp); here vertices with bit-identical positions are
// merged, so that the result is an indexed mesh (vertices (n, 3) float32, indices (m, 3)
// uint32, triangle m in the file's order) that glint.MeshBvh takes as it is.
#include <array>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include <glint/io/gltf.hpp>
#include <glint/io/obj.hpp>

#include "arrays.hpp"

namespace glint::python {

namespace {

struct BitsHash {
    std::size_t operator()(const std::array<std::uint32_t, 3>& k) const {
        return std::size_t(k[0]) * 0x9e3779b97f4a7c15ULL ^ std::size_t(k[1]) * 0xc2b2ae3d27d4eb4fULL ^ k[2];
    }
};

/// The triangles as merged vertices and indices (the dict's "vertices" and "indices").
void indexed(std::span<const TriangleVertices<float>> tris, py::dict& out) {
    std::unordered_map<std::array<std::uint32_t, 3>, std::uint32_t, BitsHash> seen;
    std::vector<float> vertices;
    py::array_t<std::uint32_t> indices({py::ssize_t(tris.size()), py::ssize_t(3)});
    std::uint32_t* idx = indices.mutable_data();
    for (const auto& t : tris)
        for (const Vec3f& p : t) {
            std::array<std::uint32_t, 3> key;
            std::memcpy(key.data(), &p[0], sizeof key);
            const auto [it, added] = seen.emplace(key, std::uint32_t(vertices.size() / 3));
            if (added) vertices.insert(vertices.end(), {p.x, p.y, p.z});
            *idx++ = it->second;
        }
    py::array_t<float> v({py::ssize_t(vertices.size() / 3), py::ssize_t(3)});
    std::memcpy(v.mutable_data(), vertices.data(), vertices.size() * sizeof(float));
    out["vertices"] = v;
    out["indices"] = indices;
}

py::array_t<std::uint32_t> array_of(const std::vector<std::uint32_t>& v) {
    py::array_t<std::uint32_t> a(py::ssize_t(v.size()));
    std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(std::uint32_t));
    return a;
}

py::tuple rgb(const Rgb<float>& c) { return py::make_tuple(c[0], c[1], c[2]); }

py::dict load_obj_arrays(const std::string& path) {
    const ObjMesh mesh = load_obj(path);
    py::dict out;
    indexed(mesh.triangles, out);
    out["material"] = array_of(mesh.material);
    out["line"] = array_of(mesh.line);
    py::list materials;
    for (const ObjMaterial& m : mesh.materials)
        materials.append(py::dict(py::arg("name") = m.name, py::arg("kd") = rgb(m.kd), py::arg("ks") = rgb(m.ks),
                                  py::arg("ke") = rgb(m.ke), py::arg("ns") = m.ns, py::arg("ni") = m.ni,
                                  py::arg("illum") = m.illum));
    out["materials"] = materials;
    out["warnings"] = py::cast(mesh.warnings);
    return out;
}

py::dict load_gltf_arrays(const std::string& path) {
    const GltfScene<float> g = read_gltf<float>(path);
    py::dict out;
    indexed(g.scene.triangles, out);
    out["material"] = array_of(g.scene.material_of);
    out["warnings"] = py::cast(g.warnings);
    if (g.has_camera) {
        const Camera<float>& c = g.scene.camera;
        out["camera"] = py::dict(py::arg("eye") = py::make_tuple(c.eye.x, c.eye.y, c.eye.z),
                                 py::arg("look_at") = py::make_tuple(c.target.x, c.target.y, c.target.z),
                                 py::arg("up") = py::make_tuple(c.up.x, c.up.y, c.up.z), py::arg("fov") = c.fov_y * 180.0f / pi<float>);
    }
    return out;
}

}  // namespace

void bind_io(py::module_& m) {
    m.def("load_obj", &load_obj_arrays, py::arg("path"),
          "An OBJ (+MTL) file as a dict: vertices (n, 3) float32, indices (m, 3) uint32 (fans of its faces),\n"
          "material (m,) uint32 into materials (dicts of name, kd, ks, ke, ns, ni, illum; the last is the\n"
          "default grey), line (m,) the OBJ line of each triangle's face, warnings. Vertex normals and\n"
          "texture coordinates are not read. Raises glint.Error naming the file and line.");
    m.def("load_gltf", &load_gltf_arrays, py::arg("path"),
          "A glTF 2.0 file (.gltf or .glb) as a dict: vertices (n, 3) float32 and indices (m, 3) uint32 in\n"
          "world space (node transforms applied), material (m,) uint32, warnings, and camera (eye, look_at,\n"
          "up, fov in degrees) when the file has one. Raises glint.Error naming the file and item.");
}

}  // namespace glint::python
