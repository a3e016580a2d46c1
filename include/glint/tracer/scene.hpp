// glint/tracer/scene.hpp: what the reference path tracer renders: triangle meshes with
// per-face materials, polygon area lights, point lights (isotropic, spot, oriented: lights/light.hpp), an optional environment map and a
// pinhole camera (core/camera.hpp); plus the scene's features, checked once, before rendering.
//
// Materials (Szécsi 2009, §1.3, and §2.1 for the combined BRDF):
//   lambertian  f = kd / pi;
//   glossy      kd / pi + ks (n + 2) / (2 pi) cos^n(alpha), alpha = angle to the mirror
//               direction (the energy-normalized Phong lobe, Lafortune and Willems 1994):
//               the two-lobe BRDF of Szécsi 2009's BRDF-selection experiments (§2.1, Fig. 2.1);
//   mirror      ideal reflection with reflectance ks;
//   dielectric  ideal refraction and reflection with Fresnel weights (index ior).
// Any material may emit (emission = radiance leaving the front face). A material's kd may be
// multiplied by a texture (tracer/texture.hpp) at the hit's texture coordinates: material_at().
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/camera.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/lights/light.hpp>
#include <glint/tracer/environment.hpp>
#include <glint/tracer/texture.hpp>

namespace glint {

enum class MaterialKind : std::uint8_t { lambertian, glossy, mirror, dielectric };

/// A surface material: its BRDF kind and parameters, and the radiance it emits.
template <Scalar T>
struct Material {
    MaterialKind kind = MaterialKind::lambertian;  ///< Which BRDF the parameters below describe.
    Rgb<T> kd{T(0.5)};      ///< Diffuse reflectance per band, in [0, 1] (lambertian, glossy).
    Rgb<T> ks{T(0)};        ///< Specular reflectance per band, in [0, 1] (glossy, mirror).
    T exponent = T(20);     ///< Glossy lobe exponent; larger is sharper.
    Rgb<T> emission{T(0)};  ///< Emitted radiance per band; zero for a non-emitter.
    T ior = T(1.5);         ///< Index of refraction of a dielectric (relative to outside).
    /// Index into Scene::textures of the texture kd is multiplied by (the base colour), or -1.
    std::int32_t kd_texture = -1;

    /// Whether the material emits (any band of `emission` above zero).
    bool emissive() const { return emission.max() > T(0); }
    /// Whether the BRDF is a delta distribution (mirror or dielectric).
    bool specular() const { return kind == MaterialKind::mirror || kind == MaterialKind::dielectric; }

    /// Diffuse material of reflectance kd, emitting `emission`.
    static Material lambertian(const Rgb<T>& kd, const Rgb<T>& emission = Rgb<T>(T(0))) {
        return Material{MaterialKind::lambertian, kd, Rgb<T>(T(0)), T(20), emission, T(1.5)};
    }
    /// Diffuse kd plus a glossy lobe of reflectance ks and the given exponent.
    static Material glossy(const Rgb<T>& kd, const Rgb<T>& ks, T exponent) {
        return Material{MaterialKind::glossy, kd, ks, exponent, Rgb<T>(T(0)), T(1.5)};
    }
    /// Perfect mirror of reflectance ks.
    static Material mirror(const Rgb<T>& ks) {
        return Material{MaterialKind::mirror, Rgb<T>(T(0)), ks, T(0), Rgb<T>(T(0)), T(1.5)};
    }
    /// Smooth glass-like interface of index of refraction `ior` (Fresnel reflection and refraction).
    static Material dielectric(T ior) {
        return Material{MaterialKind::dielectric, Rgb<T>(T(0)), Rgb<T>(T(1)), T(0), Rgb<T>(T(0)), ior};
    }
};

/// A planar convex polygon that emits `emission` from its front side (the side its normal,
/// from the vertices' counter-clockwise order, points to).
template <Scalar T>
struct AreaLight {
    std::vector<Vec3<T>> vertices;  ///< Polygon corners in world space, counter-clockwise seen from the front.
    Rgb<T> emission{T(0)};          ///< Emitted radiance per band, uniform over the front side.
    Vec3<T> normal{0, 0, 1};        ///< Unit normal of the front side.
    T area = 0;                     ///< Polygon area in squared world units.
};

/// Which capabilities a scene uses, checked once before rendering (the path tracer skips the
/// point lights and the environment where a scene has none; glint-render's roulette choice
/// reads `grey`).
struct SceneFeatures {
    bool environment = false;   ///< The scene has an environment map.
    bool point_lights = false;  ///< The scene has at least one point light.
    bool area_lights = false;   ///< The scene has at least one area light.
    bool specular = false;      ///< Some material is specular (mirror or dielectric).
    /// Every reflectance (kd, ks) equal in all bands, so that every walk's throughput stays
    /// grey whatever the lights' colours: the spectral roulettes then reduce exactly to the
    /// classic ones.
    bool grey = true;
};

/// A renderable scene: triangles with per-triangle materials and area lights, point lights,
/// an optional environment map and a camera, all in world space. validate() checks it.
template <Scalar T>
class Scene {
public:
    std::string name = "scene";  ///< Name used in error messages and reports.
    std::vector<TriangleVertices<T>> triangles;  ///< Every triangle's vertices, world space.
    /// Per triangle, the unit normals at its three corners (an OBJ's `vn`), in the order of
    /// its vertices; empty where the scene has none (then it is shaded with the geometric
    /// normal). See shading_normal().
    std::vector<std::array<Vec3<T>, 3>> corner_normals;
    /// Per triangle, the texture coordinates of its three corners, in the order of its
    /// vertices; empty where the scene has none. See texcoord().
    std::vector<std::array<Vec2<T>, 3>> corner_uvs;
    std::vector<Texture<T>> textures;  ///< Images the materials' kd_texture refer to.
    std::vector<std::uint32_t> material_of;  ///< Per triangle: index into `materials`.
    std::vector<Material<T>> materials;  ///< Materials the triangles refer to.
    std::vector<AreaLight<T>> area_lights;  ///< Emitting polygons, each made of scene triangles.
    std::vector<std::int32_t> light_of;  ///< Per triangle: index of its area light, or -1.
    std::vector<PointLight<T>> point_lights;  ///< Point lights (no geometry).
    std::optional<EnvironmentMap<T>> environment;  ///< Distant illumination, if any.
    Camera<T> camera;  ///< The view rendered.

    /// Adds a material, returns its index.
    std::uint32_t add_material(const Material<T>& m) {
        materials.push_back(m);
        return static_cast<std::uint32_t>(materials.size() - 1);
    }

    /// Adds a planar convex polygon (counter-clockwise seen from its front) as triangles of
    /// material `m`; an emissive material also makes it an area light.
    void add_polygon(std::span<const Vec3<T>> poly, std::uint32_t m) {
        if (poly.size() < 3) throw Error("Scene::add_polygon: a polygon needs at least 3 vertices");
        if (m >= materials.size()) throw Error("Scene::add_polygon: material " + std::to_string(m) + " does not exist");
        std::int32_t light = -1;
        if (materials[m].emissive()) {
            AreaLight<T> l;
            l.vertices.assign(poly.begin(), poly.end());
            l.emission = materials[m].emission;
            Vec3<T> n(0);
            for (std::size_t i = 1; i + 1 < poly.size(); ++i) n += glm::cross(poly[i] - poly[0], poly[i + 1] - poly[0]);
            l.area = glm::length(n) * T(0.5);
            l.normal = safe_normalize(n);
            if (!(l.area > T(0))) throw Error("Scene::add_polygon: emissive polygon has zero area");
            area_lights.push_back(std::move(l));
            light = static_cast<std::int32_t>(area_lights.size() - 1);
        }
        for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
            triangles.push_back({poly[0], poly[i], poly[i + 1]});
            material_of.push_back(m);
            light_of.push_back(light);
        }
    }
    /// Adds the planar quad a, b, c, d (in order) with material index m, as add_polygon does.
    void add_quad(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c, const Vec3<T>& d, std::uint32_t m) {
        const std::array<Vec3<T>, 4> q{a, b, c, d};
        add_polygon(q, m);
    }

    /// Checks consistency; throws glint::Error with what is wrong.
    void validate() const {
        if (triangles.empty()) throw Error("scene '" + name + "' has no triangles");
        if (material_of.size() != triangles.size() || light_of.size() != triangles.size())
            throw Error("scene '" + name + "': per-triangle arrays disagree in size");
        for (std::uint32_t m : material_of)
            if (m >= materials.size()) throw Error("scene '" + name + "': a triangle has no material");
        for (std::size_t i = 0; i < point_lights.size(); ++i) point_lights[i].validate(i);
        if (!corner_normals.empty() && corner_normals.size() != triangles.size())
            throw Error("scene '" + name + "': " + std::to_string(corner_normals.size()) + " triangles' corner normals for " +
                        std::to_string(triangles.size()) + " triangles");
        for (std::size_t i = 0; i < corner_normals.size(); ++i)
            for (const Vec3<T>& c : corner_normals[i])
                if (!(std::abs(glm::length(c) - T(1)) < T(1e-3)))
                    throw Error("scene '" + name + "': triangle " + std::to_string(i) + " has a corner normal of length " +
                                std::to_string(glm::length(c)) + " (unit normals are needed)");
        validate_textures();
    }

    /// Checks the texture coordinates, the textures and the materials' references to them.
    void validate_textures() const {
        const std::string where = "scene '" + name + "': ";
        if (!corner_uvs.empty() && corner_uvs.size() != triangles.size())
            throw Error(where + std::to_string(corner_uvs.size()) + " triangles' texture coordinates for " +
                        std::to_string(triangles.size()) + " triangles");
        for (std::size_t i = 0; i < corner_uvs.size(); ++i)
            for (const Vec2<T>& c : corner_uvs[i])
                if (!(std::isfinite(c.x) && std::isfinite(c.y)))
                    throw Error(where + "triangle " + std::to_string(i) + " has a texture coordinate that is not finite");
        for (std::size_t t = 0; t < textures.size(); ++t)
            textures[t].validate(where + "texture " + std::to_string(t) + " ('" + textures[t].source + "')");
        for (std::size_t m = 0; m < materials.size(); ++m) {
            const std::int32_t k = materials[m].kd_texture;
            if (k < -1 || k >= std::int32_t(textures.size()))
                throw Error(where + "material " + std::to_string(m) + " refers to texture " + std::to_string(k) + " of " +
                            std::to_string(textures.size()));
            if (k >= 0 && corner_uvs.empty())
                throw Error(where + "material " + std::to_string(m) + " has a texture but no triangle has texture coordinates");
        }
    }

    /// Which capabilities the scene uses (scans materials and lights; linear cost).
    SceneFeatures features() const {
        SceneFeatures f;
        f.environment = environment.has_value();
        f.point_lights = !point_lights.empty();
        f.area_lights = !area_lights.empty();
        auto grey = [](const Rgb<T>& s) { return s[0] == s[1] && s[1] == s[2]; };
        for (const auto& m : materials) {
            f.specular |= m.specular();
            f.grey &= grey(m.kd) && grey(m.ks) && (m.kd_texture < 0 || textures[std::size_t(m.kd_texture)].grey());
        }
        return f;
    }

    /// Unit geometric normal of triangle i (from its vertex order).
    Vec3<T> normal(std::size_t i) const {
        const auto& t = triangles[i];
        return safe_normalize(glm::cross(t[1] - t[0], t[2] - t[0]));
    }

    /// Gives the triangles that have no corner normals yet (those after the last that has),
    /// up to triangle `end`, their geometric normal at each corner: a scene that mixes meshes
    /// with and without vertex normals shades the latter flat.
    void fill_corner_normals(std::size_t end = std::size_t(-1)) {
        while (corner_normals.size() < std::min(end, triangles.size())) {
            const Vec3<T> g = normal(corner_normals.size());
            corner_normals.push_back({g, g, g});
        }
    }

    /// Gives the triangles that have no texture coordinates yet, up to triangle `end`, the
    /// coordinates (0, 0) at every corner (as fill_corner_normals does for normals).
    void fill_corner_uvs(std::size_t end = std::size_t(-1)) {
        corner_uvs.resize(std::max(corner_uvs.size(), std::min(end, triangles.size())));
    }

    /// The texture coordinates at barycentrics (u, v) of triangle i, interpolated from its
    /// corners; (0, 0) where the scene has none.
    Vec2<T> texcoord(std::size_t i, T u, T v) const {
        if (corner_uvs.empty()) return Vec2<T>(T(0));
        const auto& c = corner_uvs[i];
        return c[0] * (T(1) - u - v) + c[1] * u + c[2] * v;
    }

    /// The material of triangle i at barycentrics (u, v): materials[material_of[i]], its kd
    /// multiplied by its texture (Material::kd_texture) at the point's texture coordinates.
    [[gnu::always_inline]] Material<T> material_at(std::size_t i, T u, T v) const {
        Material<T> m = materials[material_of[i]];
        if (m.kd_texture >= 0) m.kd *= textures[std::size_t(m.kd_texture)].lookup(texcoord(i, u, v));
        return m;
    }

    /// Throws glint::Error naming `who` if some material has a texture: for the integrators
    /// that keep a material by its index (photon maps, VPLs), which would shade untextured.
    void require_untextured(const std::string& who) const {
        for (std::size_t m = 0; m < materials.size(); ++m)
            if (materials[m].kd_texture >= 0)
                throw Error(who + ": scene '" + name + "' has a textured material (" + std::to_string(m) +
                            "); textures are applied by the path tracer only");
    }

    /// The shading normal at barycentrics (u, v) of triangle i (the point (1 - u - v) v0 +
    /// u v1 + v v2, as hits report it): its corner normals interpolated and normalized
    /// (Phong 1975), turned to the side of `ng`, the unit geometric normal on the side being
    /// shaded. `ng` itself where the scene has no corner normals, or where they cancel.
    [[gnu::always_inline]] Vec3<T> shading_normal(std::size_t i, T u, T v, const Vec3<T>& ng) const {
        if (corner_normals.empty()) return ng;
        const auto& c = corner_normals[i];
        const Vec3<T> s = safe_normalize(c[0] * (T(1) - u - v) + c[1] * u + c[2] * v, Vec3<T>(0));
        const T side = glm::dot(s, ng);
        return side > T(0) ? s : side < T(0) ? -s : ng;
    }

    /// Total emitted power of the area lights per band (Phi = pi Le A for a Lambertian
    /// emitter), the total surface area and the area-weighted mean albedo: the inputs of
    /// Szécsi 2009, §2.3's scene-wide radiance estimate.
    void radiance_estimate_inputs(Rgb<T>& power, T& area, Rgb<T>& mean_albedo) const {
        power = Rgb<T>(T(0));
        for (const auto& l : area_lights) power += l.emission * (pi<T> * l.area);
        area = 0;
        mean_albedo = Rgb<T>(T(0));
        for (std::size_t i = 0; i < triangles.size(); ++i) {
            const auto& t = triangles[i];
            const T a = glm::length(glm::cross(t[1] - t[0], t[2] - t[0])) * T(0.5);
            const Material<T>& m = materials[material_of[i]];
            area += a;
            mean_albedo += (m.kd * (m.kd_texture < 0 ? Rgb<T>(T(1)) : textures[std::size_t(m.kd_texture)].mean()) + m.ks) * a;
        }
        if (area > T(0)) mean_albedo /= area;
        mean_albedo = min(mean_albedo, Rgb<T>(T(0.999)));
    }
};

}  // namespace glint
