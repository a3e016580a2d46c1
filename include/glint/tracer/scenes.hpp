// glint/tracer/scenes.hpp: the built-in scenes, generated in code so that tests need no
// files, and scenes made from OBJ meshes.
//
//   cornell         the Cornell box, measured geometry (Cornell University Program of
//                   Computer Graphics, as converted by Cardenas and McGuire 2011) and
//                   measured reflectances (white 0.725 0.71 0.68, red 0.63 0.065 0.05,
//                   green 0.14 0.45 0.091; light 17 12 4);
//   cornell-glossy  the same box with diffuse + Phong materials, for the BRDF-selection
//                   experiment of Szécsi 2009, §2.1 (Fig. 2.1);
//   furnace         Szécsi 2009, §2.2's saturated furnace: a closed room whose six walls carry
//                   the six permutations of the albedo (1.0, 0.5, 0.2) over RGB and emit
//                   1 - albedo, so the radiance is exactly 1 everywhere in every band
//                   (L = E + a L has the solution L = 1 when E = 1 - a);
//   arealight       a room lit by one large area light covering a wall, with occluding
//                   columns (Szécsi 2009, §3.2, Fig. 3.4);
//   envmap          a sphere and a box on a ground plane under a procedural sky with a sun
//                   (Szécsi 2009, §3.3, Fig. 3.7), or under a given lat-long EXR;
//   cornell-caustics        the Cornell box's walls with a glass sphere (dielectric, ior 1.5,
//                           96 x 192 quads) and a mirror cube instead of the two boxes, lit by
//                           the same small area light: the caustic scene of photon mapping
//                           (Jensen 2001, ch. 9; Larsen 2004, ch. 4);
//   cornell-caustics-point  the same lit by an isotropic point light just below the ceiling
//                           (intensity Le A of the area light: the same irradiance straight
//                           below), whose caustics a path tracer cannot sample at all;
//   hall, kitchen, lie-hall  many-light scenes (lights/scenes.hpp).
//
// insert_mesh() adds a mesh (an OBJ's triangles) to a scene, scaled to a footprint and standing
// on a floor point: glint-render --insert-mesh puts one on the Cornell box's free floor
// (cornell_mesh_placement), the mesh scene of the Cycles comparison (tools/peer_cycles.py).
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/lights/scenes.hpp>
#include <glint/tracer/choice.hpp>
#include <glint/tracer/environment.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// The procedural sky of the envmap scene (and of OBJ scenes that do not emit): a blue
/// gradient, a dark ground and a small bright sun.
template <Scalar T>
EnvironmentMap<T> default_sky() {
    return EnvironmentMap<T>::sky(256, 128, Vec3<T>(0.5, 0.6, 0.3), Rgb<float>(4000.0f, 3600.0f, 3000.0f), 0.03f,
                                  Rgb<float>(0.25f, 0.45f, 0.9f), Rgb<float>(0.8f, 0.85f, 0.95f), Rgb<float>(0.15f));
}

/// A loaded scene (an OBJ, a glTF) made ready to render: default_sky() where nothing emits
/// (no area or point light) and, where its file gave no camera (`has_camera` false), the
/// frame_box() camera of its triangles' bounds.
template <Scalar T>
void sky_and_framing(Scene<T>& s, bool has_camera) {
    if (s.area_lights.empty() && s.point_lights.empty()) s.environment = default_sky<T>();
    if (has_camera) return;
    AABB<T> box;
    for (const auto& t : s.triangles)
        for (const auto& p : t) box.extend(p);
    s.camera = frame_box(box);
}

namespace detail {

/// An axis-aligned box [lo, hi] rotated by `angle` about the vertical axis through its
/// centre; faces counter-clockwise from outside.
template <Scalar T>
void add_box(Scene<T>& s, const Vec3<T>& lo, const Vec3<T>& hi, T angle, std::uint32_t m) {
    const Vec3<T> c = (lo + hi) * T(0.5);
    const T ca = std::cos(angle), sa = std::sin(angle);
    auto p = [&](int i) {
        const Vec3<T> q((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
        const Vec3<T> r = q - c;
        return c + Vec3<T>(ca * r.x + sa * r.z, r.y, -sa * r.x + ca * r.z);
    };
    const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) s.add_quad(p(f[0]), p(f[1]), p(f[2]), p(f[3]), m);
}

/// A UV sphere of `rings` x `segments` quads (split into triangles).
template <Scalar T>
void add_sphere(Scene<T>& s, const Vec3<T>& centre, T radius, int rings, int segments, std::uint32_t m) {
    auto p = [&](int i, int j) {
        const T theta = pi<T> * T(i) / T(rings), phi = T(2) * pi<T> * T(j) / T(segments);
        return centre + Vec3<T>(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)) * radius;
    };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const std::array<Vec3<T>, 3> a{p(i, j), p(i, j + 1), p(i + 1, j + 1)};
            const std::array<Vec3<T>, 3> b{p(i, j), p(i + 1, j + 1), p(i + 1, j)};
            if (i != 0) s.add_polygon(a, m);
            if (i != rings - 1) s.add_polygon(b, m);
        }
}

/// A quad whose vertex order is flipped, if needed, so that its normal points to `toward`.
template <Scalar T>
void add_quad_facing(Scene<T>& s, Vec3<T> a, Vec3<T> b, Vec3<T> c, Vec3<T> d, const Vec3<T>& toward,
                     std::uint32_t m) {
    if (glm::dot(glm::cross(b - a, c - a), toward - a) < T(0)) std::swap(b, d);
    s.add_quad(a, b, c, d, m);
}

/// The Cornell box's walls (floor, ceiling, back, green right, red left), as cornell() has them.
template <Scalar T>
void add_cornell_walls(Scene<T>& s, std::uint32_t w, std::uint32_t r, std::uint32_t g) {
    using V = Vec3<T>;
    s.add_quad(V(-1.01, 0, 0.99), V(1.00, 0, 0.99), V(1.00, 0, -1.04), V(-0.99, 0, -1.04), w);         // floor
    s.add_quad(V(-1.02, 1.99, 0.99), V(-1.02, 1.99, -1.04), V(1.00, 1.99, -1.04), V(1.00, 1.99, 0.99), w);  // ceiling
    s.add_quad(V(-0.99, 0, -1.04), V(1.00, 0, -1.04), V(1.00, 1.99, -1.04), V(-1.02, 1.99, -1.04), w); // back
    s.add_quad(V(1.00, 0, -1.04), V(1.00, 0, 0.99), V(1.00, 1.99, 0.99), V(1.00, 1.99, -1.04), g);      // right
    s.add_quad(V(-1.01, 0, 0.99), V(-0.99, 0, -1.04), V(-1.02, 1.99, -1.04), V(-1.02, 1.99, 0.99), r);  // left
}

template <Scalar T>
Scene<T> cornell(bool glossy) {
    Scene<T> s;
    s.name = glossy ? "cornell-glossy" : "cornell";
    const Rgb<T> white(T(0.725), T(0.71), T(0.68)), red(T(0.63), T(0.065), T(0.05)),
        green(T(0.14), T(0.45), T(0.091));
    auto surface = [&](const Rgb<T>& kd) {
        // Glossy variant: the same total reflectance split 60/40 between a diffuse and a
        // Phong lobe of exponent 40.
        return s.add_material(glossy ? Material<T>::glossy(kd * T(0.6), kd * T(0.4), T(40)) : Material<T>::lambertian(kd));
    };
    const auto w = surface(white), r = surface(red), g = surface(green);
    const auto light = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.78)), Rgb<T>(T(17), T(12), T(4))));
    using V = Vec3<T>;
    add_cornell_walls(s, w, r, g);
    // Short box.
    s.add_quad(V(0.53, 0.60, 0.75), V(0.70, 0.60, 0.17), V(0.13, 0.60, 0.00), V(-0.05, 0.60, 0.57), w);
    s.add_quad(V(-0.05, 0, 0.57), V(-0.05, 0.60, 0.57), V(0.13, 0.60, 0.00), V(0.13, 0, 0.00), w);
    s.add_quad(V(0.53, 0, 0.75), V(0.53, 0.60, 0.75), V(-0.05, 0.60, 0.57), V(-0.05, 0, 0.57), w);
    s.add_quad(V(0.70, 0, 0.17), V(0.70, 0.60, 0.17), V(0.53, 0.60, 0.75), V(0.53, 0, 0.75), w);
    s.add_quad(V(0.13, 0, 0.00), V(0.13, 0.60, 0.00), V(0.70, 0.60, 0.17), V(0.70, 0, 0.17), w);
    // Tall box.
    s.add_quad(V(-0.53, 1.20, 0.09), V(0.04, 1.20, -0.09), V(-0.14, 1.20, -0.67), V(-0.71, 1.20, -0.49), w);
    s.add_quad(V(-0.53, 0, 0.09), V(-0.53, 1.20, 0.09), V(-0.71, 1.20, -0.49), V(-0.71, 0, -0.49), w);
    s.add_quad(V(-0.71, 0, -0.49), V(-0.71, 1.20, -0.49), V(-0.14, 1.20, -0.67), V(-0.14, 0, -0.67), w);
    s.add_quad(V(-0.14, 0, -0.67), V(-0.14, 1.20, -0.67), V(0.04, 1.20, -0.09), V(0.04, 0, -0.09), w);
    s.add_quad(V(0.04, 0, -0.09), V(0.04, 1.20, -0.09), V(-0.53, 1.20, 0.09), V(-0.53, 0, 0.09), w);
    // Light, facing down, just below the ceiling.
    add_quad_facing(s, V(-0.24, 1.98, 0.16), V(-0.24, 1.98, -0.22), V(0.23, 1.98, -0.22), V(0.23, 1.98, 0.16),
                    V(0, 0, 0), light);
    s.camera = Camera<T>{V(0, 1, 3.9), V(0, 1, 0), V(0, 1, 0), T(0.68)};
    return s;
}

/// The caustic scenes: a glass sphere (radius 0.33 on the floor, right front) and a mirror cube
/// (0.55 wide, left back, turned 0.35 rad) in the Cornell box, lit by its small area light or
/// by an isotropic point light of intensity Le A at the light's centre, 0.08 below the ceiling.
template <Scalar T>
Scene<T> cornell_caustics(bool point) {
    Scene<T> s;
    s.name = point ? "cornell-caustics-point" : "cornell-caustics";
    add_cornell_walls(s, s.add_material(Material<T>::lambertian(Rgb<T>(T(0.725), T(0.71), T(0.68)))),
                      s.add_material(Material<T>::lambertian(Rgb<T>(T(0.63), T(0.065), T(0.05)))),
                      s.add_material(Material<T>::lambertian(Rgb<T>(T(0.14), T(0.45), T(0.091)))));
    using V = Vec3<T>;
    const auto glass = s.add_material(Material<T>::dielectric(T(1.5)));
    const auto mirror = s.add_material(Material<T>::mirror(Rgb<T>(T(0.95))));
    add_sphere(s, V(0.38, 0.335, 0.28), T(0.33), 96, 192, glass);
    add_box(s, V(-0.72, 0, -0.62), V(-0.17, 0.55, -0.07), T(0.35), mirror);
    const Rgb<T> Le(T(17), T(12), T(4));
    const T area = T(0.47) * T(0.38);
    if (point) {
        s.point_lights.push_back(PointLight<T>::isotropic(V(-0.005, 1.91, -0.03), Le * area));
    } else {
        const auto light = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.78)), Le));
        add_quad_facing(s, V(-0.24, 1.98, 0.16), V(-0.24, 1.98, -0.22), V(0.23, 1.98, -0.22), V(0.23, 1.98, 0.16),
                        V(0, 0, 0), light);
    }
    s.camera = Camera<T>{V(0, 1, 3.9), V(0, 1, 0), V(0, 1, 0), T(0.68)};
    return s;
}

template <Scalar T>
Scene<T> furnace() {
    Scene<T> s;
    s.name = "furnace";
    const T a[3] = {T(1.0), T(0.5), T(0.2)};
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    std::uint32_t m[6];
    for (int i = 0; i < 6; ++i) {
        const Rgb<T> albedo(a[perms[i][0]], a[perms[i][1]], a[perms[i][2]]);
        m[i] = s.add_material(Material<T>::lambertian(albedo, Rgb<T>(T(1)) - albedo));
    }
    using V = Vec3<T>;
    // Faces of the cube [-1,1]^3, emitting towards its centre.
    const V o(0);
    add_quad_facing(s, V(-1, -1, -1), V(1, -1, -1), V(1, -1, 1), V(-1, -1, 1), o, m[0]);  // floor
    add_quad_facing(s, V(-1, 1, -1), V(-1, 1, 1), V(1, 1, 1), V(1, 1, -1), o, m[1]);      // ceiling
    add_quad_facing(s, V(-1, -1, -1), V(-1, 1, -1), V(1, 1, -1), V(1, -1, -1), o, m[2]);  // back
    add_quad_facing(s, V(-1, -1, 1), V(1, -1, 1), V(1, 1, 1), V(-1, 1, 1), o, m[3]);      // front
    add_quad_facing(s, V(-1, -1, -1), V(-1, -1, 1), V(-1, 1, 1), V(-1, 1, -1), o, m[4]);  // left
    add_quad_facing(s, V(1, -1, -1), V(1, 1, -1), V(1, 1, 1), V(1, -1, 1), o, m[5]);      // right
    s.camera = Camera<T>{V(0, 0, 0.5), V(0.2, -0.1, -1), V(0, 1, 0), T(1.2)};
    return s;
}

template <Scalar T>
Scene<T> arealight() {
    Scene<T> s;
    s.name = "arealight";
    const auto w = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.7))));
    const auto col = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.6), T(0.55), T(0.5))));
    const auto light = s.add_material(Material<T>::lambertian(Rgb<T>(T(0)), Rgb<T>(T(3))));
    using V = Vec3<T>;
    // Room [-3,3] x [0,3] x [-3,3]; the wall x = -3 is entirely an area light facing +x.
    s.add_quad(V(-3, 0, -3), V(-3, 0, 3), V(3, 0, 3), V(3, 0, -3), w);  // floor (up)
    s.add_quad(V(-3, 3, -3), V(3, 3, -3), V(3, 3, 3), V(-3, 3, 3), w);  // ceiling
    s.add_quad(V(-3, 0, -3), V(3, 0, -3), V(3, 3, -3), V(-3, 3, -3), w);  // back
    s.add_quad(V(3, 0, -3), V(3, 0, 3), V(3, 3, 3), V(3, 3, -3), w);    // right
    s.add_quad(V(-3, 0, 3), V(3, 0, 3), V(3, 3, 3), V(-3, 3, 3), w);    // front (behind the camera)
    add_quad_facing(s, V(-3, 0, -3), V(-3, 3, -3), V(-3, 3, 3), V(-3, 0, 3), V(0, 1.5, 0), light);  // light wall
    // Columns between the light and the room.
    for (int i = 0; i < 4; ++i) {
        const T z = T(-2.25) + T(1.5) * T(i);
        add_box(s, V(-1.8, 0, z - 0.2), V(-1.4, 2.6, z + 0.2), T(0.3) * T(i), col);
    }
    s.camera = Camera<T>{V(2.6, 2.4, 2.6), V(-0.8, 0.6, -0.4), V(0, 1, 0), T(1.0)};
    return s;
}

template <Scalar T>
Scene<T> envmap(std::optional<EnvironmentMap<T>> map = std::nullopt) {
    Scene<T> s;
    s.name = "envmap";
    const auto ground = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.5))));
    const auto ball = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.8), T(0.3), T(0.2))));
    const auto box = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.3), T(0.5), T(0.8))));
    using V = Vec3<T>;
    s.add_quad(V(-6, 0, -6), V(-6, 0, 6), V(6, 0, 6), V(6, 0, -6), ground);
    add_sphere(s, V(-0.7, 1, 0), T(1), 24, 48, ball);
    add_box(s, V(0.7, 0, -0.6), V(1.9, 1.2, 0.6), T(0.5), box);
    if (map) {
        s.environment = std::move(map);
    } else {
        s.environment = default_sky<T>();
    }
    s.camera = Camera<T>{V(0, 2.2, 6), V(0, 0.8, 0), V(0, 1, 0), T(0.75)};
    return s;
}

}  // namespace detail

/// Where insert_mesh() puts a mesh: uniformly scaled so that the larger of its bounding
/// box's horizontal (x, z) extents is `size`, and moved so that the box's bottom centre is at
/// `base` (the mesh stands on a floor through `base`; y is up, as in every built-in scene).
template <Scalar T>
struct MeshPlacement {
    Vec3<T> base{0};  ///< Scene point where the mesh's bounding-box bottom centre lands.
    T size = T(1);    ///< Larger horizontal (x or z) extent after scaling, in scene units, > 0.
};

/// Adds the triangles `mesh` (vertex order kept) to `s` with the material `m`, placed by `p`;
/// returns the material's index. Throws glint::Error for an empty or flat-footprint mesh, a
/// non-positive size or a non-finite vertex.
template <Scalar T>
std::uint32_t insert_mesh(Scene<T>& s, std::span<const TriangleVertices<T>> mesh, const Material<T>& m,
                          const MeshPlacement<T>& p) {
    if (mesh.empty()) throw Error("insert_mesh: the mesh has no triangles");
    if (!(p.size > T(0)) || !std::isfinite(double(p.size)))
        throw Error("insert_mesh: size " + std::to_string(double(p.size)) + " is not positive");
    AABB<T> box;
    for (const auto& t : mesh)
        for (const auto& v : t) {
            if (!std::isfinite(double(v.x)) || !std::isfinite(double(v.y)) || !std::isfinite(double(v.z)))
                throw Error("insert_mesh: a vertex is not finite");
            box.extend(v);
        }
    const Vec3<T> e = box.extent();
    const T footprint = std::max(e.x, e.z);
    if (!(footprint > T(0))) throw Error("insert_mesh: the mesh has no horizontal extent");
    const T scale = p.size / footprint;
    const Vec3<T> bottom((box.lo.x + box.hi.x) * T(0.5), box.lo.y, (box.lo.z + box.hi.z) * T(0.5));
    const std::uint32_t mi = s.add_material(m);
    for (const auto& t : mesh) {
        const std::array<Vec3<T>, 3> q{p.base + (t[0] - bottom) * scale, p.base + (t[1] - bottom) * scale,
                                       p.base + (t[2] - bottom) * scale};
        s.add_polygon(q, mi);
    }
    return mi;
}

/// The Cornell box's free floor between the short box, the tall box and the red wall, where
/// glint-render --insert-mesh puts a mesh (0.7 wide: at least 0.1 clear of the walls and boxes).
template <Scalar T>
MeshPlacement<T> cornell_mesh_placement() {
    return MeshPlacement<T>{Vec3<T>(T(-0.5), T(0), T(0.45)), T(0.7)};
}

/// The built-in scenes by name.
template <Scalar T>
std::span<const Choice<Scene<T> (*)()>> scene_choices() {
    static constexpr Choice<Scene<T> (*)()> table[] = {
        {"cornell", "the Cornell box", [] { return detail::cornell<T>(false); }},
        {"cornell-glossy", "the Cornell box with glossy boxes", [] { return detail::cornell<T>(true); }},
        {"furnace", "a closed room of saturated albedos whose radiance is 1 everywhere", [] { return detail::furnace<T>(); }},
        {"arealight", "a room lit by a large area light, with occluding columns", [] { return detail::arealight<T>(); }},
        {"envmap", "a sphere and a box under a sky with a sun (or an EXR map)", [] { return detail::envmap<T>(); }},
        {"cornell-caustics", "the Cornell box with a glass sphere and a mirror cube, small area light",
         [] { return detail::cornell_caustics<T>(false); }},
        {"cornell-caustics-point", "the same lit by a point light", [] { return detail::cornell_caustics<T>(true); }},
        {"hall", "a hall of columns with 800 point and spot lights", [] { return hall_scene<T>(); }},
        {"kitchen", "a kitchen lit by 72 disk area lights", [] { return kitchen_scene<T>(); }},
        {"lie-hall", "a hall with 100 point lights and many occluders", [] { return lie_hall_scene<T>(); }},
    };
    return table;
}

/// Names accepted by builtin_scene().
inline const std::vector<std::string>& builtin_scene_names() {
    static const std::vector<std::string> names = [] {
        std::vector<std::string> v;
        for (const auto& c : scene_choices<float>()) v.emplace_back(c.name);
        return v;
    }();
    return names;
}

/// A built-in scene by name; throws glint::Error listing the names for an unknown one.
template <Scalar T>
Scene<T> builtin_scene(const std::string& name) {
    return find_choice(scene_choices<T>(), "scene", name).make();
}

}  // namespace glint
