// glint/io/scene_json_read.hpp: reads back the JSON that io/scene_json.hpp writes (glint-render
// --export-scene), so that a built scene is a file: the camera, the materials, the area and
// point lights, the triangles with their materials and area lights, corner normals, texture
// coordinates and textures where the file has them, the image size and the path-length cap.
// A float scene reads back exactly (9 significant digits round-trip every
// float); a double scene to 9 digits.
//
// A hand-written scene may also name meshes by path: "meshes": [{"path": "bunny.obj",
// "material": 2}] loads each OBJ (io/obj.hpp; a relative path is taken from the scene file's
// folder) and gives all its triangles material 2 (the OBJ's own materials are not used; its
// vertex normals are), after the inline triangles; an emissive material makes each of them an
// area light. Triangles without normals where others have them are shaded flat. "triangles"
// may then be left out (with "material_of" and "light_of").
//
// Files written before `light_of` was exported get it rebuilt: each emissive triangle belongs
// to the first area light, from the previous triangle's on, whose polygon has its three
// vertices (as Scene::add_polygon fans a polygon). Unknown members are ignored (peers may add
// their own). Every error is a glint::Error "FILE:LINE: ..." naming the member.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/io/json.hpp>
#include <glint/io/obj.hpp>
#include <glint/io/scene_json.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// A scene file: the scene and the image and tracer settings it was exported with.
template <Scalar T>
struct SceneFile {
    Scene<T> scene;      ///< Geometry, materials, lights and camera, as written.
    SceneJsonView view;  ///< Image size and vertex cap the scene was exported with.
};

namespace detail {

struct SceneJsonReader {
    const std::string& file;

    [[noreturn]] void fail(const JsonValue& at, const std::string& what) const {
        throw Error(file + ":" + std::to_string(at.line) + ": " + what);
    }

    const JsonValue& member(const JsonValue& obj, const char* key, JsonValue::Kind kind) const {
        if (obj.kind != JsonValue::Kind::object) fail(obj, std::string("expected an object with '") + key + "'");
        const JsonValue* v = obj.find(key);
        if (!v) fail(obj, std::string("member '") + key + "' is missing");
        if (v->kind != kind) fail(*v, std::string("member '") + key + "' has the wrong type");
        return *v;
    }

    double number(const JsonValue& v, const char* what) const {
        if (v.kind != JsonValue::Kind::number || !std::isfinite(v.number)) fail(v, std::string(what) + " is not a finite number");
        return v.number;
    }
    double field(const JsonValue& obj, const char* key) const { return number(member(obj, key, JsonValue::Kind::number), key); }

    long long integer(const JsonValue& v, const char* what, long long lo, long long hi) const {
        const double x = number(v, what);
        if (x != std::floor(x) || x < double(lo) || x > double(hi))
            fail(v, std::string(what) + " = " + std::to_string(x) + " is not an integer in [" + std::to_string(lo) + ", " +
                        std::to_string(hi) + "]");
        return static_cast<long long>(x);
    }

    /// `n` numbers from the array v (exactly n).
    template <Scalar T>
    void numbers(const JsonValue& v, T* out, std::size_t n, const char* what) const {
        if (v.kind != JsonValue::Kind::array || v.items.size() != n)
            fail(v, std::string(what) + " needs " + std::to_string(n) + " numbers");
        for (std::size_t i = 0; i < n; ++i) out[i] = T(number(v.items[i], what));
    }
    template <Scalar T>
    Vec3<T> vec3(const JsonValue& obj, const char* key) const {
        T a[3];
        numbers(member(obj, key, JsonValue::Kind::array), a, 3, key);
        return Vec3<T>(a[0], a[1], a[2]);
    }
    template <Scalar T>
    Rgb<T> rgb(const JsonValue& obj, const char* key) const {
        const Vec3<T> v = vec3<T>(obj, key);
        return Rgb<T>(v.x, v.y, v.z);
    }
    std::string name(const JsonValue& obj, const char* key, std::initializer_list<const char*> allowed) const {
        const JsonValue& v = member(obj, key, JsonValue::Kind::string);
        std::string list;
        for (const char* a : allowed) {
            if (v.string == a) return v.string;
            list += (list.empty() ? "" : ", ") + std::string(a);
        }
        fail(v, std::string(key) + " '" + v.string + "' is not one of " + list);
    }
};

template <Scalar T>
void read_json_textures(const SceneJsonReader& r, const JsonValue& doc, Scene<T>& s) {
    const JsonValue* textures = doc.find("textures");
    if (!textures) return;
    if (textures->kind != JsonValue::Kind::array) r.fail(*textures, "textures must be an array");
    for (const JsonValue& t : textures->items) {
        Texture<T> tex;
        tex.width = int(r.integer(r.member(t, "width", JsonValue::Kind::number), "width", 1, 1 << 16));
        tex.height = int(r.integer(r.member(t, "height", JsonValue::Kind::number), "height", 1, 1 << 16));
        tex.nearest = r.name(t, "filter", {"linear", "nearest"}) == "nearest";
        const JsonValue& wrap = r.member(t, "wrap", JsonValue::Kind::array);
        if (wrap.items.size() != 2) r.fail(wrap, "wrap needs two modes (u, v)");
        for (std::size_t k = 0; k < 2; ++k) {
            const auto modes = {TextureWrap::repeat, TextureWrap::mirrored_repeat, TextureWrap::clamp};
            const auto mode = std::find_if(modes.begin(), modes.end(), [&](TextureWrap w) {
                return wrap.items[k].kind == JsonValue::Kind::string && wrap.items[k].string == texture_wrap_name(w);
            });
            if (mode == modes.end()) r.fail(wrap.items[k], "a wrap mode is not one of repeat, mirrored_repeat, clamp");
            (k ? tex.wrap_v : tex.wrap_u) = *mode;
        }
        if (const JsonValue* source = t.find("source"); source && source->kind == JsonValue::Kind::string) tex.source = source->string;
        std::vector<T> texels(std::size_t(tex.width) * std::size_t(tex.height) * 3);
        r.numbers(r.member(t, "texels", JsonValue::Kind::array), texels.data(), texels.size(), "texels");
        for (std::size_t i = 0; i < texels.size(); i += 3) tex.texels.emplace_back(texels[i], texels[i + 1], texels[i + 2]);
        try {
            tex.validate("texture " + std::to_string(s.textures.size()));
        } catch (const Error& e) {
            r.fail(t, e.what());
        }
        s.textures.push_back(std::move(tex));
    }
}

template <Scalar T>
void read_json_materials(const SceneJsonReader& r, const JsonValue& doc, Scene<T>& s) {
    read_json_textures(r, doc, s);
    for (const JsonValue& m : r.member(doc, "materials", JsonValue::Kind::array).items) {
        const std::string kind = r.name(m, "kind", {"lambertian", "glossy", "mirror", "dielectric"});
        Material<T> mat;
        mat.kind = kind == "lambertian" ? MaterialKind::lambertian
                   : kind == "glossy"   ? MaterialKind::glossy
                   : kind == "mirror"   ? MaterialKind::mirror
                                        : MaterialKind::dielectric;
        mat.kd = r.rgb<T>(m, "kd");
        mat.ks = r.rgb<T>(m, "ks");
        mat.exponent = T(r.field(m, "exponent"));
        mat.emission = r.rgb<T>(m, "emission");
        mat.ior = T(r.field(m, "ior"));
        if (mat.kd.min() < T(0) || mat.ks.min() < T(0) || mat.emission.min() < T(0)) r.fail(m, "a material has a negative colour");
        if (const JsonValue* k = m.find("kd_texture"))
            mat.kd_texture = std::int32_t(r.integer(*k, "kd_texture", -1, (long long)s.textures.size() - 1));
        s.add_material(mat);
    }
}

template <Scalar T>
void read_json_lights(const SceneJsonReader& r, const JsonValue& doc, Scene<T>& s) {
    for (const JsonValue& l : r.member(doc, "area_lights", JsonValue::Kind::array).items) {
        AreaLight<T> a;
        for (const JsonValue& v : r.member(l, "vertices", JsonValue::Kind::array).items) {
            T p[3];
            r.numbers(v, p, 3, "vertices");
            a.vertices.emplace_back(p[0], p[1], p[2]);
        }
        if (a.vertices.size() < 3) r.fail(l, "an area light needs at least 3 vertices");
        a.emission = r.rgb<T>(l, "emission");
        a.normal = r.vec3<T>(l, "normal");
        a.area = T(r.field(l, "area"));
        if (!(a.area > T(0))) r.fail(l, "an area light's area is not positive");
        s.area_lights.push_back(std::move(a));
    }
    for (const JsonValue& l : r.member(doc, "point_lights", JsonValue::Kind::array).items) {
        const std::string kind = r.name(l, "kind", {"isotropic", "spot", "cosine"});
        PointLight<T> p;
        p.kind = kind == "isotropic" ? PointLightKind::isotropic : kind == "spot" ? PointLightKind::spot : PointLightKind::cosine;
        p.position = r.vec3<T>(l, "position");
        p.intensity = r.rgb<T>(l, "intensity");
        p.axis = r.vec3<T>(l, "axis");
        p.cos_outer = T(r.field(l, "cos_outer"));
        p.cos_inner = T(r.field(l, "cos_inner"));
        s.point_lights.push_back(p);
    }
}

/// light_of for a file without it (see the file comment).
template <Scalar T>
void rebuild_light_of(const SceneJsonReader& r, const JsonValue& doc, Scene<T>& s) {
    std::size_t light = 0;
    auto holds = [&](const AreaLight<T>& l, const TriangleVertices<T>& t) {
        return std::all_of(t.begin(), t.end(), [&](const Vec3<T>& p) {
            return std::find(l.vertices.begin(), l.vertices.end(), p) != l.vertices.end();
        });
    };
    for (std::size_t i = 0; i < s.triangles.size(); ++i) {
        if (!s.materials[s.material_of[i]].emissive()) continue;
        while (light < s.area_lights.size() && !holds(s.area_lights[light], s.triangles[i])) ++light;
        if (light == s.area_lights.size()) r.fail(doc, "emissive triangle " + std::to_string(i) + " lies in no area light");
        s.light_of[i] = std::int32_t(light);
    }
}

/// The optional member `key`: one row per triangle of its corners' vectors (V: Vec3 for
/// normals, nine numbers a row; Vec2 for texture coordinates, six), appended to `out`.
template <class V>
void read_json_corner_rows(const SceneJsonReader& r, const JsonValue& doc, const char* key, std::size_t triangles,
                           std::vector<std::array<V, 3>>& out) {
    constexpr int n = V::length();
    const JsonValue* rows = doc.find(key);
    if (!rows) return;
    if (rows->kind != JsonValue::Kind::array || rows->items.size() != triangles)
        r.fail(*rows, std::string(key) + " needs one entry (" + (n == 3 ? "nine" : "six") + " numbers) per triangle");
    for (const JsonValue& row : rows->items) {
        typename V::value_type a[3 * n];
        r.numbers(row, a, 3 * n, key);
        std::array<V, 3> corners;
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < n; ++c) corners[std::size_t(k)][c] = a[n * k + c];
        out.push_back(corners);
    }
}

template <Scalar T>
void read_json_triangles(const SceneJsonReader& r, const JsonValue& doc, Scene<T>& s) {
    if (!doc.find("triangles") && doc.find("meshes")) return;
    const auto& tris = r.member(doc, "triangles", JsonValue::Kind::array).items;
    const auto& mats = r.member(doc, "material_of", JsonValue::Kind::array).items;
    if (mats.size() != tris.size()) r.fail(doc, "material_of has " + std::to_string(mats.size()) + " entries for " +
                                                    std::to_string(tris.size()) + " triangles");
    for (std::size_t i = 0; i < tris.size(); ++i) {
        T a[9];
        r.numbers(tris[i], a, 9, "triangles");
        s.triangles.push_back({Vec3<T>(a[0], a[1], a[2]), Vec3<T>(a[3], a[4], a[5]), Vec3<T>(a[6], a[7], a[8])});
        s.material_of.push_back(std::uint32_t(r.integer(mats[i], "material_of", 0, (long long)s.materials.size() - 1)));
    }
    read_json_corner_rows(r, doc, "corner_normals", tris.size(), s.corner_normals);
    read_json_corner_rows(r, doc, "corner_uvs", tris.size(), s.corner_uvs);
    s.light_of.assign(tris.size(), -1);
    const JsonValue* lights = doc.find("light_of");
    if (!lights) return rebuild_light_of(r, doc, s);
    if (lights->kind != JsonValue::Kind::array || lights->items.size() != tris.size())
        r.fail(*lights, "light_of needs one entry per triangle");
    for (std::size_t i = 0; i < tris.size(); ++i)
        s.light_of[i] = std::int32_t(r.integer(lights->items[i], "light_of", -1, (long long)s.area_lights.size() - 1));
}

/// The "meshes" an OBJ path each (see the file comment).
template <Scalar T>
void read_json_meshes(const SceneJsonReader& r, const JsonValue& doc, Scene<T>& s) {
    const JsonValue* meshes = doc.find("meshes");
    if (!meshes) return;
    if (meshes->kind != JsonValue::Kind::array) r.fail(*meshes, "meshes must be an array");
    const auto slash = r.file.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "" : r.file.substr(0, slash + 1);
    for (const JsonValue& m : meshes->items) {
        const std::string& path = r.member(m, "path", JsonValue::Kind::string).string;
        const auto mat = std::uint32_t(r.integer(r.member(m, "material", JsonValue::Kind::number), "material", 0,
                                                 (long long)s.materials.size() - 1));
        const ObjMesh obj = load_obj(path.starts_with('/') ? path : dir + path);
        const bool normals = !obj.normals.empty() || !s.corner_normals.empty();
        if (normals) s.fill_corner_normals();  // the triangles before, flat where they have none
        for (const auto& t : obj.triangles) {
            const std::array<Vec3<T>, 3> tri{Vec3<T>(t[0]), Vec3<T>(t[1]), Vec3<T>(t[2])};
            if (s.materials[mat].emissive() && !(glm::length(glm::cross(tri[1] - tri[0], tri[2] - tri[0])) > T(0)))
                r.fail(m, "mesh '" + path + "' has an emissive triangle of zero area");
            s.add_polygon(tri, mat);
        }
        for (const auto& c : obj.normals) s.corner_normals.push_back({Vec3<T>(c[0]), Vec3<T>(c[1]), Vec3<T>(c[2])});
        if (normals) s.fill_corner_normals();  // this mesh's, flat where it has none
        if (!s.corner_uvs.empty()) s.fill_corner_uvs();  // the OBJ's texture coordinates are not read
    }
}

}  // namespace detail

/// Parses the text of a scene file; `file` names it in errors.
template <Scalar T>
SceneFile<T> parse_scene_json(std::string_view text, const std::string& file) {
    const JsonValue doc = parse_json(text, file);
    const detail::SceneJsonReader r{file};
    SceneFile<T> out;
    Scene<T>& s = out.scene;
    s.name = doc.kind == JsonValue::Kind::object && doc.find("name") && doc.find("name")->kind == JsonValue::Kind::string
                 ? doc.find("name")->string : file;
    out.view.width = int(r.integer(r.member(doc, "width", JsonValue::Kind::number), "width", 1, 1 << 16));
    out.view.height = int(r.integer(r.member(doc, "height", JsonValue::Kind::number), "height", 1, 1 << 16));
    out.view.max_depth = int(r.integer(r.member(doc, "max_depth", JsonValue::Kind::number), "max_depth", 1, 1 << 24));
    const JsonValue& cam = r.member(doc, "camera", JsonValue::Kind::object);
    s.camera = Camera<T>{r.vec3<T>(cam, "eye"), r.vec3<T>(cam, "target"), r.vec3<T>(cam, "up"), T(r.field(cam, "fov_y"))};
    if (!(s.camera.fov_y > T(0) && s.camera.fov_y < pi<T>)) r.fail(cam, "fov_y is not in (0, pi)");
    detail::read_json_materials(r, doc, s);
    detail::read_json_lights(r, doc, s);
    detail::read_json_triangles(r, doc, s);
    detail::read_json_meshes(r, doc, s);
    try {
        s.validate();
    } catch (const Error& e) {
        throw Error(file + ": " + e.what());
    }
    return out;
}

/// Reads the scene file `path` (what write_scene_json writes). Throws glint::Error.
template <Scalar T>
SceneFile<T> read_scene_json(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error("read_scene_json(" + path + "): cannot read the file");
    std::stringstream text;
    text << f.rdbuf();
    return parse_scene_json<T>(text.str(), path);
}

}  // namespace glint
