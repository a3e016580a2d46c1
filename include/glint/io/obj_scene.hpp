// glint/io/obj_scene.hpp: a path-tracing scene from a loaded OBJ (io/obj.hpp): each MTL
// material mapped onto glint's materials, emissive faces as area lights, a sky where nothing
// emits, a camera framing the mesh, the OBJ's vertex normals as the scene's corner normals
// (shading normals) and its texture coordinates and map_Kd images as kd's textures.
// glint-render --mesh and the Python module's render() use it.
//
// The material mapping (MTL illumination models as in the Wavefront MTL specification):
//   illum 5 (reflection, ray traced)       -> mirror of reflectance Ks (0.9 grey where Ks = 0);
//   illum 7 (refraction, ray traced)       -> dielectric of index Ni (1.5 where Ni <= 1);
//   Ks > 0 and Ns > 0 (any other illum)    -> glossy: Kd diffuse plus Ks Phong lobe of exponent Ns;
//   otherwise                              -> Lambertian Kd.
// Ke is every material's emission. map_Kd multiplies kd (io/image_file.hpp loads it, sRGB);
// a mirror or glass, which has no kd, ignores it.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include <glint/io/image_file.hpp>
#include <glint/io/obj.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/scenes.hpp>

namespace glint {

/// glint's material for an OBJ/MTL material (the mapping of the header comment).
inline Material<float> scene_material(const ObjMaterial& m) {
    Material<float> mat = Material<float>::lambertian(m.kd, m.ke);
    if (m.illum == 5) mat = Material<float>::mirror(m.ks.max() > 0 ? m.ks : Rgb<float>(0.9f));
    else if (m.illum == 7) mat = Material<float>::dielectric(m.ni > 1.0f ? m.ni : 1.5f);
    else if (m.ks.max() > 0 && m.ns > 0) mat = Material<float>::glossy(m.kd, m.ks, m.ns);
    mat.emission = m.ke;
    return mat;
}

/// Loads each material's map_Kd (once per file) into s.textures and points the material's kd
/// at it; a textured material in an OBJ without texture coordinates is an error.
inline void obj_textures(const ObjMesh& mesh, Scene<float>& s) {
    std::map<std::string, std::int32_t> loaded;
    for (std::size_t i = 0; i < mesh.materials.size(); ++i) {
        const std::string& file = mesh.materials[i].map_kd;
        if (file.empty() || !(s.materials[i].kd.max() > 0.0f)) continue;
        if (mesh.uvs.empty())
            throw Error(s.name + ": material '" + mesh.materials[i].name + "' has map_Kd " + file +
                        " but no face has texture coordinates (vt)");
        const auto [it, added] = loaded.try_emplace(file, std::int32_t(s.textures.size()));
        if (added) s.textures.push_back(load_texture<float>(file));
        s.materials[i].kd_texture = it->second;
    }
}

/// The scene of a loaded OBJ, named `name`: its triangles and mapped materials (textures
/// included), its emissive faces as area lights, a sky when none emits and a framing camera
/// (sky_and_framing).
inline Scene<float> obj_scene(const ObjMesh& mesh, std::string name) {
    Scene<float> s;
    s.name = std::move(name);
    for (const ObjMaterial& m : mesh.materials) s.add_material(scene_material(m));
    obj_textures(mesh, s);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) s.add_polygon(mesh.triangles[i], mesh.material[i]);
    s.corner_normals = mesh.normals;  // add_polygon made one scene triangle per mesh triangle
    s.corner_uvs = mesh.uvs;
    sky_and_framing(s, false);
    return s;
}

}  // namespace glint
