// glint/io/scene_json.hpp: a built scene as JSON, for exporting it exactly to another
// renderer (tools/peer_cycles.py builds the same scene in Blender's Cycles from it).
//
// Written: the triangles (three vertices each, in the tracer's order, whose vertex order
// gives the geometric normal and so an emitter's front face), their corner (shading) normals
// where the scene has them (corner_normals, nine numbers per triangle like "triangles"), their
// texture coordinates where it has them (corner_uvs, six numbers per triangle), the
// material of each triangle (material_of) and its area light (light_of, -1 for none),
// the textures (width, height, filter, wrap, source, and every linear texel, row after row:
// a texture reads back exactly without its image file), the materials (kind, kd, ks, Phong
// exponent, emission, ior, and kd_texture where kd has one: the model of
// glint/tracer/scene.hpp), the area lights (polygon, emission, unit normal, area), the point
// lights (kind isotropic | spot | cosine, position, intensity, axis, cos_outer, cos_inner:
// glint/lights/light.hpp), the pinhole camera (eye, target, up, full vertical field of view
// fov_y in radians) with the image size and aspect, and the tracer's path-length cap
// max_depth. Numbers are written with 9 significant digits, which round-trips every float.
// io/scene_json_read.hpp reads the file back.
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// Image and tracer settings that the exported scene is rendered with.
struct SceneJsonView {
    /// Image width in pixels, > 0 (write_scene_json throws otherwise); the writer also stores
    /// width / height as the camera's aspect.
    int width = 256, height = 256;
    /// \var height
    /// Image height in pixels, > 0 (write_scene_json throws otherwise).
    int max_depth = 64;  ///< Cap on a walk's vertices (PathTracerSettings::max_depth), > 0.
};

namespace detail {

inline const char* material_kind_name(MaterialKind k) {
    switch (k) {
        case MaterialKind::lambertian: return "lambertian";
        case MaterialKind::glossy: return "glossy";
        case MaterialKind::mirror: return "mirror";
        default: return "dielectric";
    }
}

/// Writes a finite number; a NaN or infinity throws (JSON has none).
template <Scalar T>
void json_number(std::ostream& out, T v, const char* what) {
    if (!std::isfinite(double(v)))
        throw Error(std::string("write_scene_json: ") + what + " has a non-finite value " + std::to_string(double(v)));
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.9g", double(v));
    out << buf;
}

/// Writes `v` as a JSON string (quotes and backslashes escaped, control characters dropped).
inline void json_string(std::ostream& out, const std::string& v) {
    out << '"';
    for (const char c : v) {
        if (c == '"' || c == '\\') out << '\\';
        if (static_cast<unsigned char>(c) >= 0x20) out << c;
    }
    out << '"';
}

/// Writes "[a, b, ...]" of `n` finite numbers.
template <Scalar T>
void json_numbers(std::ostream& out, const T* v, std::size_t n, const char* what) {
    out << '[';
    for (std::size_t i = 0; i < n; ++i) {
        out << (i ? ", " : "");
        json_number(out, v[i], what);
    }
    out << ']';
}

template <Scalar T>
void json_value(std::ostream& out, T v, const char* what) {
    json_number(out, v, what);
}

template <Scalar T>
void json_value(std::ostream& out, const Vec3<T>& v, const char* what) {
    const T a[3] = {v.x, v.y, v.z};
    json_numbers(out, a, 3, what);
}

template <Scalar T>
void json_value(std::ostream& out, const Rgb<T>& c, const char* what) {
    const T a[3] = {c[0], c[1], c[2]};
    json_numbers(out, a, 3, what);
}

/// Writes `, "name": value`.
template <class V>
void json_field(std::ostream& out, const char* name, const V& v) {
    out << ", \"" << name << "\": ";
    json_value(out, v, name);
}

/// Writes `"key": [` one `{...}` per item of `items`, each written by `item`, `],`.
template <class Items, class WriteItem>
void json_objects(std::ostream& out, const char* key, const Items& items, WriteItem item) {
    out << "  \"" << key << "\": [\n";
    for (std::size_t i = 0; i < items.size(); ++i) {
        out << "    {";
        item(items[i]);
        out << (i + 1 < items.size() ? "},\n" : "}\n");
    }
    out << "  ],\n";
}

inline const char* point_light_kind_name(PointLightKind k) {
    switch (k) {
        case PointLightKind::isotropic: return "isotropic";
        case PointLightKind::spot: return "spot";
        default: return "cosine";
    }
}

template <Scalar T>
void json_materials(std::ostream& out, const Scene<T>& s) {
    json_objects(out, "materials", s.materials, [&](const Material<T>& m) {
        out << "\"kind\": \"" << material_kind_name(m.kind) << '"';
        json_field(out, "kd", m.kd);
        json_field(out, "ks", m.ks);
        json_field(out, "exponent", m.exponent);
        json_field(out, "emission", m.emission);
        json_field(out, "ior", m.ior);
        if (m.kd_texture >= 0) out << ", \"kd_texture\": " << m.kd_texture;
    });
}

template <Scalar T>
void json_lights(std::ostream& out, const Scene<T>& s) {
    json_objects(out, "area_lights", s.area_lights, [&](const AreaLight<T>& l) {
        out << "\"vertices\": [";
        for (std::size_t k = 0; k < l.vertices.size(); ++k) {
            out << (k ? ", " : "");
            json_value(out, l.vertices[k], "vertices");
        }
        out << ']';
        json_field(out, "emission", l.emission);
        json_field(out, "normal", l.normal);
        json_field(out, "area", l.area);
    });
    json_objects(out, "point_lights", s.point_lights, [&](const PointLight<T>& l) {
        out << "\"kind\": \"" << point_light_kind_name(l.kind) << '"';
        json_field(out, "position", l.position);
        json_field(out, "intensity", l.intensity);
        json_field(out, "axis", l.axis);
        json_field(out, "cos_outer", l.cos_outer);
        json_field(out, "cos_inner", l.cos_inner);
    });
}

/// Writes "[a, b, ...]" of integers, 32 a line.
template <class Int>
void json_integers(std::ostream& out, const std::vector<Int>& v) {
    out << '[';
    for (std::size_t i = 0; i < v.size(); ++i) out << (i ? (i % 32 ? ", " : ",\n    ") : "") << v[i];
    out << ']';
}

/// Member `name`: one row per triangle of its three corners' vectors (points, normals: nine
/// numbers; texture coordinates: six).
template <class V>
void json_corner_rows(std::ostream& out, const char* name, const std::vector<std::array<V, 3>>& rows) {
    constexpr int n = V::length();
    out << "  \"" << name << "\": [\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
        typename V::value_type a[3 * n];
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < n; ++c) a[n * k + c] = rows[i][std::size_t(k)][c];
        out << "    ";
        json_numbers(out, a, 3 * n, name);
        out << (i + 1 < rows.size() ? ",\n" : "\n");
    }
    out << "  ],\n";
}

inline const char* texture_wrap_name(TextureWrap w) {
    return w == TextureWrap::clamp ? "clamp" : w == TextureWrap::mirrored_repeat ? "mirrored_repeat" : "repeat";
}

template <Scalar T>
void json_textures(std::ostream& out, const Scene<T>& s) {
    json_objects(out, "textures", s.textures, [&](const Texture<T>& t) {
        out << "\"width\": " << t.width << ", \"height\": " << t.height << ", \"filter\": \"" << (t.nearest ? "nearest" : "linear")
            << "\", \"wrap\": [\"" << texture_wrap_name(t.wrap_u) << "\", \"" << texture_wrap_name(t.wrap_v) << "\"], \"source\": ";
        json_string(out, t.source);
        std::vector<T> texels;
        for (const Rgb<T>& c : t.texels) texels.insert(texels.end(), {c[0], c[1], c[2]});
        out << ", \"texels\": ";
        json_numbers(out, texels.data(), texels.size(), "texels");
    });
}

template <Scalar T>
void json_triangles(std::ostream& out, const Scene<T>& s) {
    json_corner_rows(out, "triangles", s.triangles);
    if (!s.corner_normals.empty()) json_corner_rows(out, "corner_normals", s.corner_normals);
    if (!s.corner_uvs.empty()) json_corner_rows(out, "corner_uvs", s.corner_uvs);
    out << "  \"material_of\": ";
    json_integers(out, s.material_of);
    out << ",\n  \"light_of\": ";
    json_integers(out, s.light_of);
    out << "\n";
}

}  // namespace detail

/// Writes `s` as JSON (see the file comment). Throws glint::Error for an inconsistent scene,
/// an environment map (not exported), or a non-finite number.
template <Scalar T>
void write_scene_json(std::ostream& out, const Scene<T>& s, const SceneJsonView& view) {
    s.validate();
    if (s.environment) throw Error("write_scene_json: scene '" + s.name + "' has an environment map, which is not exported");
    if (view.width <= 0 || view.height <= 0 || view.max_depth <= 0)
        throw Error("write_scene_json: image " + std::to_string(view.width) + "x" + std::to_string(view.height) +
                    " or max_depth " + std::to_string(view.max_depth) + " is not positive");
    out << "{\n  \"name\": ";
    detail::json_string(out, s.name);
    out << ",\n  \"width\": " << view.width << ",\n  \"height\": " << view.height
        << ",\n  \"aspect\": ";
    detail::json_number(out, T(view.width) / T(view.height), "aspect");
    out << ",\n  \"max_depth\": " << view.max_depth << ",\n  \"camera\": {\"eye\": ";
    detail::json_value(out, s.camera.eye, "eye");
    detail::json_field(out, "target", s.camera.target);
    detail::json_field(out, "up", s.camera.up);
    detail::json_field(out, "fov_y", s.camera.fov_y);
    out << "},\n";
    if (!s.textures.empty()) detail::json_textures(out, s);
    detail::json_materials(out, s);
    detail::json_lights(out, s);
    detail::json_triangles(out, s);
    out << "}\n";
}

/// write_scene_json to the file `path`; throws glint::Error naming the file if it cannot be written.
template <Scalar T>
void write_scene_json(const std::string& path, const Scene<T>& s, const SceneJsonView& view) {
    std::ofstream f(path);
    if (!f) throw Error("write_scene_json: cannot open '" + path + "' for writing");
    write_scene_json(f, s, view);
    f.flush();
    if (!f) throw Error("write_scene_json: writing '" + path + "' failed");
}

}  // namespace glint
