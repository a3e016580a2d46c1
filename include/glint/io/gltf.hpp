// glint/io/gltf.hpp: a glTF 2.0 scene (.gltf with its buffers, or .glb) as a glint Scene,
// read through tinygltf (Debian libtinygltf-dev, a shared library: link TinyGLTF::TinyGLTF,
// which glint::io does). The format: the Khronos glTF 2.0 specification (cited as glTF 2.0);
// lights: its KHR_lights_punctual extension.
//
//   Scene<float> s = glint::load_gltf<float>("room.glb");          // the scene alone
//   GltfScene<float> g = glint::read_gltf<float>("room.gltf");     // plus warnings, camera, aspect
//
// What is read, from the default scene (or scene 0; without scenes, every root node):
//  - nodes: the whole hierarchy, each node's `matrix` or its translation * rotation * scale
//    (glTF 2.0, §3.5.2), composed from the root; a world matrix of negative determinant
//    mirrors, so its triangles' vertex order is swapped to keep the front face (§3.7.2.1);
//  - meshes: primitives of mode TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN (POSITION: VEC3
//    float; indices: unsigned byte, short or int, or none; NORMAL: VEC3 float, the scene's
//    corner normals, flat where a primitive has none; TEXCOORD_0: VEC2 float or normalized
//    unsigned byte or short, the scene's corner texture coordinates); emissive triangles
//    become area lights, one per triangle, emitting from their front face (doubleSided is
//    ignored);
//  - materials (base = baseColorFactor's RGB, alpha ignored; m = metallic, r = roughness,
//    alpha = r^2 as glTF 2.0, Appendix B, defines it; F0 = 0.04 for dielectrics, ibid.):
//      metal (m >= 0.5), r < mirror_roughness: mirror, ks = base;
//      metal, rougher:                 glossy, kd = base (1 - m), ks = base m + 0.04 (1 - m);
//      dielectric (m < 0.5), r >= diffuse_roughness: Lambertian, kd = base;
//      dielectric, smoother:           glossy, kd = 0.96 base, ks = 0.04;
//      KHR_materials_transmission factor >= 0.5: dielectric, ior from KHR_materials_ior (1.5);
//    the glossy lobe's Phong exponent n = 2 / alpha^2 - 2 (the Phong-Beckmann correspondence
//    of Walter et al. 2007, §5.2), clamped to [1, 10^4]; emission = emissiveFactor times
//    KHR_materials_emissive_strength's factor times emission_scale (radiance, as Blender's
//    exporter writes an emission strength); baseColorTexture (its image decoded by tinygltf,
//    sRGB, and its sampler's filter and wrap modes: tracer/texture.hpp) multiplies kd, not ks
//    (a mirror ignores it, with a warning); the other textures are ignored with a warning;
//  - the first perspective camera met in the node walk: eye at the node's origin, looking
//    down its -Z with +Y up (§3.10), fov_y = yfov; aspectRatio is returned (GltfScene::aspect);
//  - KHR_lights_punctual point and spot lights at their node, spots along its -Z; intensity
//    in candela (lm/sr) times watts_per_lumen (default 1/683 W/lm, the candela's definition)
//    times the colour gives glint's W/sr. Spots: outerConeAngle and innerConeAngle are
//    glint's cones; glint's spot keeps a cos(theta) factor and a smoothstep edge where the
//    extension suggests none and a squared linear edge (lights/light.hpp): equal on the axis,
//    dimmer off it. `range` is ignored (inverse-square everywhere); directional lights are
//    skipped with a warning (glint has none).
// Every error is a glint::Error naming the file and the item: a missing or unparsable file,
// a node cycle, a non-finite transform, a primitive of points or lines, an accessor of the
// wrong type, out of its buffer, sparse, with an index past the vertices or a non-finite
// position, an emissive triangle of zero area, an image that cannot be read, a textured
// primitive without TEXCOORD_0.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <tiny_gltf.h>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/io/gltf_accessors.hpp>
#include <glint/lights/light.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// How glTF's quantities become glint's (see the file comment).
struct GltfOptions {
    double watts_per_lumen = 1.0 / 683.0;  ///< light intensity: candela to W/sr
    double emission_scale = 1.0;           ///< emissive radiance factor
    double mirror_roughness = 0.1;         ///< metals smoother than this are mirrors
    double diffuse_roughness = 0.5;        ///< dielectrics at least this rough are Lambertian
};

/// What read_gltf() returns: the scene and what the file says beyond it.
template <Scalar T>
struct GltfScene {
    Scene<T> scene;  ///< Geometry, materials, area and punctual lights, and the camera if any.
    bool has_camera = false;  ///< false: scene.camera is the default one
    T aspect = T(0);          ///< the camera's aspectRatio (width / height), 0 if not given
    /// Everything read but skipped or approximated (textures, directional lights, ...), one
    /// message per item naming the file; empty when the scene is exact.
    std::vector<std::string> warnings;
};

namespace detail {

struct GltfContext {
    const tinygltf::Model& model;
    const std::string& file;
    const GltfOptions& options;
    std::vector<std::string>& warnings;
    std::vector<std::int64_t> materials;  // glTF material -> glint material (-1: not yet added)
    std::vector<std::int64_t> textures;   // glTF texture -> glint texture (-1: not yet added)
};

inline std::string gltf_material_where(const GltfContext& c, int index) {
    return c.file + ": material " + std::to_string(index) + " ('" + (index >= 0 ? c.model.materials[std::size_t(index)].name : "") + "')";
}

/// A number from an extension object's field, or `fallback`.
inline double gltf_extension_number(const tinygltf::ExtensionMap& ext, const char* name, const char* field, double fallback) {
    const auto it = ext.find(name);
    if (it == ext.end() || !it->second.IsObject() || !it->second.Has(field)) return fallback;
    const tinygltf::Value& v = it->second.Get(field);
    return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
}

/// glTF's metallic-roughness material as glint's (the mapping of the file comment).
template <Scalar T>
Material<T> gltf_material(const GltfContext& c, int index) {
    const tinygltf::Material g = index >= 0 ? c.model.materials[std::size_t(index)] : tinygltf::Material{};
    const std::string where = gltf_material_where(c, index);
    const auto& pbr = g.pbrMetallicRoughness;
    auto rgb = [&](const std::vector<double>& v, double fallback, const char* what) {
        Rgb<T> out{T(fallback)};
        for (std::size_t k = 0; k < 3 && k < v.size(); ++k) out[k] = T(v[k]);
        if (!out.is_finite() || out.min() < T(0)) throw Error(where + ": " + what + " is negative or not finite");
        return out;
    };
    const Rgb<T> base = min(rgb(pbr.baseColorFactor, 1.0, "baseColorFactor"), Rgb<T>(T(1)));
    const double strength = gltf_extension_number(g.extensions, "KHR_materials_emissive_strength", "emissiveStrength", 1.0);
    const Rgb<T> emission = rgb(g.emissiveFactor, 0.0, "emissiveFactor") * T(strength * c.options.emission_scale);
    const double m = std::clamp(pbr.metallicFactor, 0.0, 1.0), r = std::clamp(pbr.roughnessFactor, 0.0, 1.0);
    if (g.emissiveTexture.index >= 0 || pbr.metallicRoughnessTexture.index >= 0 || g.normalTexture.index >= 0)
        c.warnings.push_back(where + ": emissive, metallic-roughness and normal textures are ignored (their factors are used)");
    const double alpha = std::max(r * r, 1e-4);
    const T n = T(std::clamp(2.0 / (alpha * alpha) - 2.0, 1.0, 1e4));
    Material<T> out;
    if (gltf_extension_number(g.extensions, "KHR_materials_transmission", "transmissionFactor", 0.0) >= 0.5)
        out = Material<T>::dielectric(T(gltf_extension_number(g.extensions, "KHR_materials_ior", "ior", 1.5)));
    else if (m >= 0.5 && r < c.options.mirror_roughness) out = Material<T>::mirror(base);
    else if (m >= 0.5) out = Material<T>::glossy(base * T(1 - m), base * T(m) + Rgb<T>(T(0.04 * (1 - m))), n);
    else if (r >= c.options.diffuse_roughness) out = Material<T>::lambertian(base);
    else out = Material<T>::glossy(base * T(0.96), Rgb<T>(T(0.04)), n);
    out.emission = emission;
    return out;
}

/// The glint texture of glTF material `index`'s baseColorTexture (-1: none), added to s once
/// per glTF texture; it multiplies kd, so a material without a diffuse part ignores it.
template <Scalar T>
std::int32_t gltf_base_texture(GltfContext& c, Scene<T>& s, int index, const Material<T>& m) {
    if (index < 0) return -1;
    const tinygltf::TextureInfo& info = c.model.materials[std::size_t(index)].pbrMetallicRoughness.baseColorTexture;
    if (info.index < 0) return -1;
    const std::string where = gltf_material_where(c, index);
    if (info.texCoord != 0 || !(m.kd.max() > T(0))) {
        c.warnings.push_back(where + ": its baseColorTexture is ignored (" +
                             (info.texCoord != 0 ? "it reads TEXCOORD_" + std::to_string(info.texCoord) + "; glint reads TEXCOORD_0 only)"
                                                 : "it multiplies the diffuse reflectance, which this material has not)"));
        return -1;
    }
    if (c.textures.empty()) c.textures.assign(c.model.textures.size(), -1);
    if (std::size_t(info.index) >= c.textures.size()) throw Error(where + ": texture " + std::to_string(info.index) + " does not exist");
    std::int64_t& slot = c.textures[std::size_t(info.index)];
    if (slot < 0) {
        s.textures.push_back(gltf_texture<T>(c.model, info.index, where));
        slot = std::int64_t(s.textures.size() - 1);
    }
    return std::int32_t(slot);
}

template <Scalar T>
std::uint32_t gltf_material_index(GltfContext& c, Scene<T>& s, int index, const std::string& where) {
    if (index < -1 || index >= int(c.model.materials.size()))
        throw Error(where + ": material " + std::to_string(index) + " does not exist");
    const std::size_t slot = std::size_t(index + 1);  // slot 0: the default material
    if (c.materials.empty()) c.materials.assign(c.model.materials.size() + 1, -1);
    if (c.materials[slot] < 0) {
        Material<T> m = gltf_material<T>(c, index);
        m.kd_texture = gltf_base_texture(c, s, index, m);
        c.materials[slot] = s.add_material(m);
    }
    return std::uint32_t(c.materials[slot]);
}

/// The texture coordinates of a primitive's triangles (the last `tris.size()` of s) from its
/// TEXCOORD_0 accessor (-1: none, an error where its material is textured); a scene whose
/// primitives differ in having them gives the others (0, 0).
template <Scalar T>
void gltf_add_uvs(const GltfContext& c, Scene<T>& s, int accessor, std::size_t vertices, const std::vector<std::array<std::uint32_t, 3>>& tris,
                  bool mirrored, bool textured, const std::string& where) {
    if (accessor < 0) {
        if (textured) throw Error(where + ": its material has a baseColorTexture but the primitive has no TEXCOORD_0");
        if (!s.corner_uvs.empty()) s.fill_corner_uvs();
        return;
    }
    const std::vector<glm::dvec2> uv = gltf_vec2s(c.model, accessor, where);
    if (uv.size() != vertices)
        throw Error(where + ": " + std::to_string(uv.size()) + " texture coordinates for " + std::to_string(vertices) + " positions");
    s.fill_corner_uvs(s.triangles.size() - tris.size());
    for (const auto& t : tris) {
        std::array<Vec2<T>, 3> corner{Vec2<T>(uv[t[0]]), Vec2<T>(uv[t[1]]), Vec2<T>(uv[t[2]])};
        if (mirrored) std::swap(corner[1], corner[2]);
        s.corner_uvs.push_back(corner);
    }
}

/// The corner normals of a primitive's triangles (the last `tris.size()` of s) from its
/// NORMAL accessor (-1: none), by the inverse transpose of `world` (glTF 2.0, §3.7.2.1); a
/// scene whose primitives differ in having normals shades those without flat.
template <Scalar T>
void gltf_add_normals(const GltfContext& c, Scene<T>& s, int accessor, std::size_t vertices,
                      const std::vector<std::array<std::uint32_t, 3>>& tris, const glm::dmat4& world, const std::string& where) {
    if (accessor < 0) {
        if (!s.corner_normals.empty()) s.fill_corner_normals();
        return;
    }
    const std::vector<glm::dvec3> n = gltf_vec3s(c.model, accessor, where, "NORMAL");
    if (n.size() != vertices)
        throw Error(where + ": " + std::to_string(n.size()) + " normals for " + std::to_string(vertices) + " positions");
    const glm::dmat3 to_world = glm::transpose(glm::inverse(glm::dmat3(world)));
    const bool mirrored = glm::determinant(glm::dmat3(world)) < 0.0;  // gltf_add_mesh swapped these corners
    s.fill_corner_normals(s.triangles.size() - tris.size());  // the triangles before, flat where they have none
    for (std::size_t t = 0; t < tris.size(); ++t) {
        std::array<Vec3<T>, 3> corner;
        for (std::size_t k = 0; k < 3; ++k) {
            const glm::dvec3 w = to_world * n[tris[t][k]];
            if (!(glm::length(w) > 0.0)) throw Error(where + ": normal " + std::to_string(tris[t][k]) + " has length 0");
            corner[k] = Vec3<T>(glm::normalize(w));
        }
        if (mirrored) std::swap(corner[1], corner[2]);
        s.corner_normals.push_back(corner);
    }
}

template <Scalar T>
void gltf_add_mesh(GltfContext& c, Scene<T>& s, int mesh, const glm::dmat4& world) {
    if (mesh < 0 || std::size_t(mesh) >= c.model.meshes.size()) throw Error(c.file + ": mesh " + std::to_string(mesh) + " does not exist");
    const bool mirrored = glm::determinant(world) < 0.0;
    const auto& prims = c.model.meshes[std::size_t(mesh)].primitives;
    for (std::size_t p = 0; p < prims.size(); ++p) {
        const std::string where = c.file + ": mesh " + std::to_string(mesh) + ", primitive " + std::to_string(p);
        const auto pos = prims[p].attributes.find("POSITION");
        if (pos == prims[p].attributes.end()) throw Error(where + ": no POSITION attribute");
        const std::vector<glm::dvec3> v = gltf_vec3s(c.model, pos->second, where, "POSITION");
        const auto tris = gltf_triangles(prims[p].mode, gltf_indices(c.model, prims[p].indices, v.size(), where), where);
        const std::uint32_t m = gltf_material_index(c, s, prims[p].material, where);
        for (std::size_t t = 0; t < tris.size(); ++t) {
            std::array<Vec3<T>, 3> tri;
            for (int k = 0; k < 3; ++k) tri[std::size_t(k)] = Vec3<T>(glm::dvec3(world * glm::dvec4(v[tris[t][std::size_t(k)]], 1.0)));
            if (mirrored) std::swap(tri[1], tri[2]);
            if (s.materials[m].emissive() && !(glm::length(glm::cross(tri[1] - tri[0], tri[2] - tri[0])) > T(0)))
                throw Error(where + ": emissive triangle " + std::to_string(t) + " has zero area");
            s.add_polygon(tri, m);
        }
        const auto normal = prims[p].attributes.find("NORMAL"), uv = prims[p].attributes.find("TEXCOORD_0");
        gltf_add_normals(c, s, normal == prims[p].attributes.end() ? -1 : normal->second, v.size(), tris, world, where);
        gltf_add_uvs(c, s, uv == prims[p].attributes.end() ? -1 : uv->second, v.size(), tris, mirrored,
                     s.materials[m].kd_texture >= 0, where);
    }
}

template <Scalar T>
void gltf_set_camera(const GltfContext& c, GltfScene<T>& out, int camera, const glm::dmat4& world) {
    const std::string where = c.file + ": camera " + std::to_string(camera);
    if (camera < 0 || std::size_t(camera) >= c.model.cameras.size()) throw Error(where + " does not exist");
    const tinygltf::Camera& cam = c.model.cameras[std::size_t(camera)];
    if (cam.type != "perspective") {
        c.warnings.push_back(where + ": a " + cam.type + " camera is skipped (glint's camera is a pinhole)");
        return;
    }
    const double yfov = cam.perspective.yfov;
    if (!(yfov > 0.0 && yfov < 3.14159265358979)) throw Error(where + ": yfov " + std::to_string(yfov) + " is not in (0, pi)");
    const glm::dvec3 eye(world * glm::dvec4(0, 0, 0, 1)), ahead(world * glm::dvec4(0, 0, -1, 0)), up(world * glm::dvec4(0, 1, 0, 0));
    if (!(glm::length(ahead) > 0.0) || !(glm::length(glm::cross(ahead, up)) > 0.0))
        throw Error(where + ": its node's transform collapses the view direction");
    out.scene.camera = Camera<T>{Vec3<T>(eye), Vec3<T>(eye + glm::normalize(ahead)), Vec3<T>(glm::normalize(up)), T(yfov)};
    out.aspect = T(cam.perspective.aspectRatio > 0.0 ? cam.perspective.aspectRatio : 0.0);
    out.has_camera = true;
}

template <Scalar T>
void gltf_add_light(const GltfContext& c, Scene<T>& s, int light, const glm::dmat4& world) {
    const std::string where = c.file + ": KHR_lights_punctual light " + std::to_string(light);
    if (light < 0 || std::size_t(light) >= c.model.lights.size()) throw Error(where + " does not exist");
    const tinygltf::Light& l = c.model.lights[std::size_t(light)];
    if (l.type == "directional") {
        c.warnings.push_back(where + ": a directional light is skipped (glint has none)");
        return;
    }
    if (l.type != "point" && l.type != "spot") throw Error(where + ": unknown type '" + l.type + "'");
    Rgb<T> colour(T(1));
    for (std::size_t k = 0; k < 3 && k < l.color.size(); ++k) colour[k] = T(l.color[k]);
    const Rgb<T> intensity = colour * T(l.intensity * c.options.watts_per_lumen);
    if (!intensity.is_finite() || intensity.min() < T(0)) throw Error(where + ": colour or intensity is negative or not finite");
    const Vec3<T> p(glm::dvec3(world * glm::dvec4(0, 0, 0, 1)));
    if (l.type == "point") {
        s.point_lights.push_back(PointLight<T>::isotropic(p, intensity));
        return;
    }
    const double outer = l.spot.outerConeAngle, inner = l.spot.innerConeAngle;
    if (!(outer > 0.0 && outer <= 1.5707963267949 && inner >= 0.0 && inner <= outer))  // equal: Blender's blend 0
        throw Error(where + ": spot cones need 0 <= innerConeAngle <= outerConeAngle <= pi/2, got " + std::to_string(inner) +
                    ", " + std::to_string(outer));
    const Vec3<T> axis(glm::dvec3(world * glm::dvec4(0, 0, -1, 0)));
    if (!(glm::length(axis) > T(0))) throw Error(where + ": its node's transform collapses the spot's axis");
    PointLight<T> spot = PointLight<T>::spot(p, axis, intensity, T(outer), T(inner));
    spot.cos_outer = std::max(spot.cos_outer, T(0));  // outer = pi/2 rounds above it in float
    s.point_lights.push_back(spot);
}

/// Adds node `index` and its subtree; `path` holds the nodes above it (a cycle is an error).
template <Scalar T>
void gltf_visit(GltfContext& c, GltfScene<T>& out, int index, const glm::dmat4& parent, std::vector<int>& path) {
    const std::string where = c.file + ": node " + std::to_string(index);
    if (index < 0 || std::size_t(index) >= c.model.nodes.size()) throw Error(where + " does not exist");
    if (std::find(path.begin(), path.end(), index) != path.end()) throw Error(where + " is its own ancestor (a cycle)");
    const tinygltf::Node& n = c.model.nodes[std::size_t(index)];
    const glm::dmat4 world = parent * gltf_local_matrix(n, where);
    if (n.mesh >= 0) gltf_add_mesh(c, out.scene, n.mesh, world);
    if (n.camera >= 0 && !out.has_camera) gltf_set_camera(c, out, n.camera, world);
    const auto ext = n.extensions.find("KHR_lights_punctual");
    if (ext != n.extensions.end() && ext->second.IsObject() && ext->second.Has("light"))
        gltf_add_light(c, out.scene, ext->second.Get("light").GetNumberAsInt(), world);
    path.push_back(index);
    for (int child : n.children) gltf_visit(c, out, child, world, path);
    path.pop_back();
}

/// The root nodes: the default scene's (or scene 0's), or, without scenes, every node that
/// is no node's child.
inline std::vector<int> gltf_roots(const tinygltf::Model& m, const std::string& file) {
    if (!m.scenes.empty()) {
        const int s = m.defaultScene >= 0 ? m.defaultScene : 0;
        if (std::size_t(s) >= m.scenes.size()) throw Error(file + ": default scene " + std::to_string(s) + " does not exist");
        return m.scenes[std::size_t(s)].nodes;
    }
    std::vector<bool> child(m.nodes.size(), false);
    for (const auto& n : m.nodes)
        for (int k : n.children)
            if (k >= 0 && std::size_t(k) < child.size()) child[std::size_t(k)] = true;
    std::vector<int> roots;
    for (std::size_t i = 0; i < child.size(); ++i)
        if (!child[i]) roots.push_back(int(i));
    return roots;
}

}  // namespace detail

/// Reads the glTF 2.0 file `path` (.glb binary, otherwise JSON .gltf) as a scene, with the
/// warnings and the camera's aspect ratio (see the file comment). Throws glint::Error.
template <Scalar T>
GltfScene<T> read_gltf(const std::string& path, const GltfOptions& options = {}) {
    const tinygltf::Model model = detail::gltf_read_model(path);
    GltfScene<T> out;
    out.scene.name = path;
    detail::GltfContext c{model, path, options, out.warnings, {}, {}};
    std::vector<int> stack;
    for (int root : detail::gltf_roots(model, path)) detail::gltf_visit(c, out, root, glm::dmat4(1.0), stack);
    if (out.scene.triangles.empty()) throw Error("load_gltf(" + path + "): the scene has no triangles");
    out.scene.validate();
    return out;
}

/// The scene of the glTF 2.0 file `path` alone (read_gltf without the warnings and aspect).
template <Scalar T>
Scene<T> load_gltf(const std::string& path, const GltfOptions& options = {}) {
    return read_gltf<T>(path, options).scene;
}

}  // namespace glint
