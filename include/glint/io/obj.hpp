// glint/io/obj.hpp: Wavefront OBJ/MTL loading through tinyobjloader.
//
// Needs tinyobjloader 2 (Debian libtinyobjloader-dev): link tinyobjloader::tinyobjloader.
// Polygons are triangulated as fans; every face gets the index of its material (faces
// without one get a default grey Lambertian material). From the MTL: Kd, Ks, Ns, Ke
// (emission), Ni (index of refraction), illum and map_Kd (the diffuse texture's file, which
// io/obj_scene.hpp loads). Vertex normals (`vn`, named by faces as v//vn or v/vt/vn) become
// per-corner shading normals (ObjMesh::normals), texture coordinates (`vt`, v/vt or v/vt/vn)
// per-corner coordinates (ObjMesh::uvs).
//
// Validation (tinyobjloader reads what it cannot parse as 0 and stores a face's vertex count
// in an unsigned char, so glint scans the text itself before handing it over):
//  - every `v` needs three finite coordinates (finite as float), every face at least three
//    vertices, every face index must name an existing vertex (positive: 1..number of `v`
//    lines; negative: relative to the vertices defined before the face's line);
//  - polygons with more than 255 vertices are fan-triangulated in the text before parsing;
//  - Kd, Ks, Ke, Ns and Ni must be finite numbers, none negative, Ni above 0; Kd or Ks above
//    1 (not energy conserving) are clamped to 1 with a warning;
//  - an emissive face (a triangle of its fan) of zero area is an error; other triangles of
//    zero area are kept (no ray ever hits them) with one warning naming their count and the
//    first one's line;
//  - a face's vertex normal must exist and have a finite, non-zero length (it is normalized),
//    its texture coordinate must exist and be finite;
//  - a missing MTL file, or a material name no MTL defines, is a warning (ObjMesh::warnings):
//    its faces get the default material.
// Every error is a glint::Error naming the file, the line and the value.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <tiny_obj_loader.h>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/io/obj_scan.hpp>

namespace glint {

/// One MTL material as read, validated (see the header comment) but not yet interpreted:
/// the caller maps it to a glint Material (examples/render.cpp: illum 5 mirror, 7 glass,
/// Ks > 0 and Ns > 0 glossy, else Lambertian). The defaults are the fallback material's.
struct ObjMaterial {
    std::string name = "default";  ///< The `newmtl` name; "default" for the fallback material.
    /// Diffuse reflectance (Kd), each band in [0, 1] after clamping; mid grey by default.
    Rgb<float> kd{0.5f}, ks{0.0f}, ke{0.0f};
    /// \var ks
    /// Specular reflectance (Ks), each band in [0, 1] after clamping; none by default.
    /// \var ke
    /// Emitted radiance (Ke), each band >= 0; non-zero makes the material's faces area lights.
    float ns = 0.0f;   ///< Phong exponent (Ns), >= 0.
    float ni = 1.0f;   ///< index of refraction (Ni), > 0.
    int illum = 2;     ///< MTL illumination model (illum), passed on unchecked; 2 in the default.
    /// The diffuse texture's file (map_Kd) as a path to open: a relative name is taken from
    /// the OBJ's folder; empty without one. io/obj_scene.hpp loads it (io/image_file.hpp).
    std::string map_kd;
};

/// A triangle soup loaded by load_obj(): fan-triangulated faces with, per triangle, its
/// material and source line.
struct ObjMesh {
    /// Vertex positions of each triangle, in file units and face winding order.
    std::vector<TriangleVertices<float>> triangles;
    std::vector<std::uint32_t> material;  ///< per triangle, index into materials
    std::vector<std::uint32_t> line;      ///< per triangle, the OBJ line of its face (1-based)
    /// Per triangle, its corners' unit normals (the faces' `vn`, normalized) in the order of
    /// its vertices; a face without `vn` has its triangles' geometric normal at every corner.
    /// Empty where no face names a normal.
    std::vector<std::array<Vec3f, 3>> normals;
    /// Per triangle, its corners' texture coordinates (the faces' `vt` as (u, 1 - v): OBJ's
    /// v runs up from the image's bottom row, glint's down from its top row, as glTF's; a
    /// face without them has (0, 0) at every corner). Empty where no face names them.
    std::vector<std::array<Vec2<float>, 3>> uvs;
    /// The MTL materials in file order, then the default grey material (always last, used by
    /// faces without a known material).
    std::vector<ObjMaterial> materials;
    std::vector<std::string> warnings;    ///< missing MTL files, clamped reflectances, ...
};

namespace detail {

inline Rgb<float> obj_reflectance(const float v[3], const std::string& what, std::vector<std::string>& warnings) {
    Rgb<float> r(v[0], v[1], v[2]);
    if (r.max() > 1.0f) {
        warnings.push_back(what + " = (" + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
                           std::to_string(v[2]) + ") is above 1 (not energy conserving); clamped to 1");
        for (std::size_t c = 0; c < 3; ++c) r[c] = std::min(r[c], 1.0f);
    }
    return r;
}

/// An MTL material as glint reads it; `dir` is the OBJ's folder (with its '/', or empty),
/// where the MTL was found and relative texture paths start.
inline ObjMaterial obj_material(const tinyobj::material_t& m, const std::string& path, const std::string& dir,
                                std::vector<std::string>& warn) {
    ObjMaterial om;
    om.name = m.name;
    om.kd = obj_reflectance(m.diffuse, path + ": material '" + m.name + "' Kd", warn);
    om.ks = obj_reflectance(m.specular, path + ": material '" + m.name + "' Ks", warn);
    om.ke = Rgb<float>(m.emission[0], m.emission[1], m.emission[2]);
    om.ns = m.shininess;
    om.ni = m.ior;
    om.illum = m.illum;
    if (!m.diffuse_texname.empty()) om.map_kd = (m.diffuse_texname.starts_with('/') ? "" : dir) + m.diffuse_texname;
    return om;
}

/// Triangles of zero area met so far, and the OBJ line of the first.
struct ObjDegenerates {
    std::size_t count = 0;
    std::uint32_t first_line = 0;
};

/// A face's vertices and, where it names them, its vertex normals and texture coordinates
/// (one per vertex, or none).
struct ObjFace {
    std::vector<Vec3f> poly, normals;
    std::vector<Vec2<float>> uvs;
};

/// Face vertex k's texture coordinates into face.uvs, where it names them; a named `vt` that
/// is missing or not finite is an error naming the face's line.
inline void obj_face_uv(const tinyobj::attrib_t& attrib, const tinyobj::index_t& k, const std::string& where, ObjFace& face) {
    if (k.texcoord_index < 0) return;
    const auto j = std::size_t(k.texcoord_index);
    if (2 * j + 1 >= attrib.texcoords.size())
        throw Error(where + "the face names texture coordinate " + std::to_string(j + 1) + " but there are " +
                    std::to_string(attrib.texcoords.size() / 2) + " vt lines");
    // OBJ's v runs up from the image's bottom row; glint's (glTF's) down from its top row.
    const Vec2<float> uv(attrib.texcoords[2 * j], 1.0f - attrib.texcoords[2 * j + 1]);
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
        throw Error(where + "the face's texture coordinate vt " + std::to_string(j + 1) + " is not finite");
    face.uvs.push_back(uv);
}

/// The vertices of one face (its `count` indices) into face.poly, and its normals, unit
/// length, into face.normals where it names one at every vertex (none otherwise); a named
/// normal that is missing, not finite or of zero length is an error naming the face's line.
inline void obj_face(const tinyobj::attrib_t& attrib, std::span<const tinyobj::index_t> idx, const std::string& path,
                     std::uint32_t line, ObjFace& face) {
    face.poly.clear();
    face.normals.clear();
    face.uvs.clear();
    const std::string where = path + ":" + std::to_string(line) + ": ";
    for (const tinyobj::index_t& k : idx) {
        const auto i = std::size_t(k.vertex_index);
        if (3 * i + 2 >= attrib.vertices.size())  // the scan rules this out; never index past it
            throw Error(where + "a face parsed with vertex " + std::to_string(i + 1) + " of " +
                        std::to_string(attrib.vertices.size() / 3));
        face.poly.emplace_back(attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]);
        obj_face_uv(attrib, k, where, face);
        if (k.normal_index < 0) continue;
        const auto j = std::size_t(k.normal_index);
        if (3 * j + 2 >= attrib.normals.size())
            throw Error(where + "the face names normal " + std::to_string(j + 1) + " but there are " +
                        std::to_string(attrib.normals.size() / 3) + " vn lines");
        const Vec3f n(attrib.normals[3 * j], attrib.normals[3 * j + 1], attrib.normals[3 * j + 2]);
        const float len = glm::length(n);
        if (!(len > 0.0f) || !std::isfinite(len))
            throw Error(where + "the face's normal vn " + std::to_string(j + 1) + " has length " + std::to_string(len));
        face.normals.push_back(n / len);
    }
    if (face.normals.size() != face.poly.size()) face.normals.clear();  // normals at some vertices only: none
    if (face.uvs.size() != face.poly.size()) face.uvs.clear();
}

/// Appends the fan of one face (and its corner normals); throws for an emissive fan triangle
/// of zero area and counts the others.
inline void obj_add_face(ObjMesh& mesh, const ObjFace& face, std::uint32_t mat, std::uint32_t line,
                         const std::string& path, ObjDegenerates& degenerate) {
    const bool emissive = mesh.materials[mat].ke.max() > 0.0f;
    const std::vector<Vec3f>& poly = face.poly;
    for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
        const TriangleVertices<float> t{poly[0], poly[k], poly[k + 1]};
        const Vec3f cross = glm::cross(t[1] - t[0], t[2] - t[0]);
        const bool zero_area = !(glm::length(cross) * 0.5f > 0.0f);
        const Vec3f g = safe_normalize(cross);
        mesh.normals.push_back(face.normals.empty() ? std::array<Vec3f, 3>{g, g, g}
                                                    : std::array<Vec3f, 3>{face.normals[0], face.normals[k], face.normals[k + 1]});
        mesh.uvs.push_back(face.uvs.empty() ? std::array<Vec2<float>, 3>{}
                                            : std::array<Vec2<float>, 3>{face.uvs[0], face.uvs[k], face.uvs[k + 1]});
        if (zero_area && emissive)
            throw Error(path + ":" + std::to_string(line) + ": emissive face (material '" + mesh.materials[mat].name +
                        "') has a triangle of zero area");
        if (zero_area && degenerate.count++ == 0) degenerate.first_line = line;
        mesh.triangles.push_back(t);
        mesh.material.push_back(mat);
        mesh.line.push_back(line);
    }
}

}  // namespace detail

/// Loads `path` (and the MTL files it names, looked up next to it). See the header comment
/// for what is checked.
inline ObjMesh load_obj(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw Error("load_obj(" + path + "): cannot read the file");
    const detail::ObjScan scan = detail::obj_scan(path, file);
    const auto slash = path.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
    detail::ObjMaterialReader mtl(dir);
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    std::istringstream text(scan.text);
    if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &text, &mtl, false, false))
        throw Error("load_obj(" + path + "): " + (err.empty() ? "cannot parse the file" : err));
    ObjMesh mesh;
    mesh.warnings = mtl.warnings;
    for (const auto& m : materials) mesh.materials.push_back(detail::obj_material(m, path, dir, mesh.warnings));
    if (warn.find("material [") != std::string::npos)
        mesh.warnings.push_back(path + ": faces use a material no MTL file defines; they render as default grey");
    const auto default_material = static_cast<std::uint32_t>(mesh.materials.size());
    mesh.materials.push_back(ObjMaterial{});
    std::size_t face = 0;
    detail::ObjDegenerates degenerate;
    detail::ObjFace poly;
    bool any_normal = false, any_uv = false;
    for (const auto& shape : shapes) {
        std::size_t offset = 0;
        for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f, ++face) {
            const std::size_t count = shape.mesh.num_face_vertices[f];
            if (face >= scan.face_line.size()) throw Error("load_obj(" + path + "): more faces parsed than written");
            const std::uint32_t line = scan.face_line[face];
            detail::obj_face(attrib, std::span(shape.mesh.indices).subspan(offset, count), path, line, poly);
            any_normal |= !poly.normals.empty();
            any_uv |= !poly.uvs.empty();
            const int mid = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
            const std::uint32_t mat =
                mid >= 0 && std::size_t(mid) < default_material ? static_cast<std::uint32_t>(mid) : default_material;
            detail::obj_add_face(mesh, poly, mat, line, path, degenerate);
            offset += count;
        }
    }
    if (mesh.triangles.empty()) throw Error("load_obj(" + path + "): no faces");
    if (!any_normal) mesh.normals.clear();
    if (!any_uv) mesh.uvs.clear();
    if (degenerate.count > 0)
        mesh.warnings.push_back(path + ":" + std::to_string(degenerate.first_line) + ": " +
                                std::to_string(degenerate.count) + " triangle(s) of zero area, the first on this line; "
                                "kept, but no ray hits them");
    return mesh;
}

}  // namespace glint
