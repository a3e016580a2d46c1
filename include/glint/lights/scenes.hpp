// glint/lights/scenes.hpp: generated many-light scenes (Fernandez 2004's test scenes, ch. 3
// and 5, in kind, at sizes tests can render):
//   hall      a long hall of columns, each with a ring of point lights and a ring of spot
//             lights, and a grid of ceiling spots: 800 point emitters;
//   kitchen   a kitchen-like room (counters, an island, a table, a partition to a dining
//             corner) lit by 72 ceiling disk lights, each a 16-sided polygon area light (a
//             light-cluster method splits each into oriented points);
//   lie-hall  a hall with 100 point lights under the ceiling and many occluders (pillars,
//             screens, low walls): where per-cell visibility of LIE pays.
// column_sides, column_rings, pillar_sides, pillar_rings set the triangle counts: the defaults
// keep every scene under a few thousand triangles, so that tests stay fast; benchmarks pass
// larger values (bench_lights: up to about a million triangles).
// tracer/scenes.hpp's scene table lists them.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/lights/light.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

namespace detail {

/// The prism over `base` (a convex polygon in the plane y = y0, counter-clockwise seen from
/// above) up to y0 + h: its sides (each `rings` quads high), its top and, off the floor
/// (y0 > 0), its bottom.
template <Scalar T>
void add_extrusion(Scene<T>& s, std::span<const Vec3<T>> base, T h, std::uint32_t m, int rings = 1) {
    if (rings < 1) throw Error("add_extrusion: rings must be >= 1, got " + std::to_string(rings));
    const Vec3<T> up(0, h, 0);
    const std::size_t n = base.size();
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < rings; ++k) {
            const Vec3<T> lo = up * (T(k) / T(rings)), hi = up * (T(k + 1) / T(rings));
            const Vec3<T>& a = base[i];
            const Vec3<T>& b = base[(i + 1) % n];
            s.add_quad(a + lo, b + lo, b + hi, a + hi, m);  // outward for a counter-clockwise base seen from above
        }
    std::vector<Vec3<T>> top, bottom;
    for (std::size_t i = 0; i < n; ++i) top.push_back(base[i] + up);
    for (std::size_t i = n; i-- > 0;) bottom.push_back(base[i]);
    s.add_polygon(std::span<const Vec3<T>>(top), m);
    if (base[0].y > T(0)) s.add_polygon(std::span<const Vec3<T>>(bottom), m);  // off the floor: its underside shows
}

/// A regular n-gon of radius r about c in the plane y = c.y, counter-clockwise seen from
/// above (seen from below: clockwise, so as a polygon it faces up); `down` reverses it.
template <Scalar T>
std::vector<Vec3<T>> ngon(const Vec3<T>& c, T r, int n, bool down = false) {
    std::vector<Vec3<T>> v;
    for (int i = 0; i < n; ++i) {
        const T a = T(2) * pi<T> * T(down ? n - i : i) / T(n);
        v.push_back(c + Vec3<T>(r * std::cos(a), 0, -r * std::sin(a)));
    }
    return v;
}

/// An axis-aligned block [lo, hi].
template <Scalar T>
void add_block(Scene<T>& s, const Vec3<T>& lo, const Vec3<T>& hi, std::uint32_t m) {
    const std::vector<Vec3<T>> base{Vec3<T>(lo.x, lo.y, hi.z), Vec3<T>(hi.x, lo.y, hi.z), Vec3<T>(hi.x, lo.y, lo.z),
                                    Vec3<T>(lo.x, lo.y, lo.z)};
    add_extrusion(s, std::span<const Vec3<T>>(base), hi.y - lo.y, m);
}

/// The inside of the room [lo, hi]: floor, ceiling and four walls facing in, in materials
/// floor, ceiling, walls.
template <Scalar T>
void add_room(Scene<T>& s, const Vec3<T>& lo, const Vec3<T>& hi, std::uint32_t floor, std::uint32_t ceiling,
              std::uint32_t walls) {
    using V = Vec3<T>;
    s.add_quad(V(lo.x, lo.y, lo.z), V(lo.x, lo.y, hi.z), V(hi.x, lo.y, hi.z), V(hi.x, lo.y, lo.z), floor);
    s.add_quad(V(lo.x, hi.y, lo.z), V(hi.x, hi.y, lo.z), V(hi.x, hi.y, hi.z), V(lo.x, hi.y, hi.z), ceiling);
    s.add_quad(V(lo.x, lo.y, lo.z), V(hi.x, lo.y, lo.z), V(hi.x, hi.y, lo.z), V(lo.x, hi.y, lo.z), walls);  // back
    s.add_quad(V(lo.x, lo.y, hi.z), V(lo.x, hi.y, hi.z), V(hi.x, hi.y, hi.z), V(hi.x, lo.y, hi.z), walls);  // front
    s.add_quad(V(lo.x, lo.y, lo.z), V(lo.x, hi.y, lo.z), V(lo.x, hi.y, hi.z), V(lo.x, lo.y, hi.z), walls);  // left
    s.add_quad(V(hi.x, lo.y, lo.z), V(hi.x, lo.y, hi.z), V(hi.x, hi.y, hi.z), V(hi.x, hi.y, lo.z), walls);  // right
}

/// A warm-to-cool tint, varied by index, of mean 1.
template <Scalar T>
Rgb<T> tint(int i) {
    const T t = T((i * 37) % 11) / T(10);
    return Rgb<T>(T(1.15) - T(0.3) * t, T(1), T(0.85) + T(0.3) * t);
}

}  // namespace detail

/// The hall of columns: 2 rows of 10 columns (column_sides-gons, column_rings quads high),
/// each with a ring of 12 point lights at 3 m and of 12 spots at 5.5 m aiming down and out,
/// and a 10 x 32 grid of ceiling spots: 800 emitters.
template <Scalar T>
Scene<T> hall_scene(int column_sides = 10, int column_rings = 1) {
    Scene<T> s;
    s.name = "hall";
    using V = Vec3<T>;
    const auto floor = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.55), T(0.5), T(0.45))));
    const auto wall = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.7))));
    const auto stone = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.75), T(0.7), T(0.6))));
    detail::add_room(s, V(-8, 0, -24), V(8, 8, 24), floor, wall, wall);
    for (int row = 0; row < 2; ++row)
        for (int k = 0; k < 10; ++k) {
            const V c(row ? T(4) : T(-4), 0, T(-19.8) + T(4.4) * T(k));
            const auto base = detail::ngon(c, T(0.45), column_sides);
            detail::add_extrusion(s, std::span<const V>(base), T(8), stone, column_rings);
            for (int j = 0; j < 12; ++j) {
                const T a = T(2) * pi<T> * (T(j) + T(0.5) * T(row)) / T(12);
                const V out(std::cos(a), 0, std::sin(a));
                const int id = (row * 10 + k) * 24 + j;
                s.point_lights.push_back(PointLight<T>::isotropic(c + out * T(0.7) + V(0, 3, 0), detail::tint<T>(id) * T(0.6)));
                s.point_lights.push_back(PointLight<T>::spot(c + out * T(0.7) + V(0, 5.5, 0), out + V(0, -1.2, 0),
                                                             detail::tint<T>(id + 12) * T(4), T(0.5), T(0.3)));
            }
        }
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 32; ++j)
            s.point_lights.push_back(PointLight<T>::spot(V(T(-7.2) + T(1.6) * T(i), T(7.9), T(-23.25) + T(1.5) * T(j)), V(0, -1, 0),
                                                         detail::tint<T>(i * 32 + j) * T(3), T(0.35), T(0.2)));
    for (int k = 0; k < 6; ++k)  // benches between the rows
        detail::add_block(s, V(T(-1.2), 0, T(-18) + T(7) * T(k)), V(T(1.2), T(0.5), T(-17.4) + T(7) * T(k)), stone);
    s.camera = Camera<T>{V(T(-1.5), T(2.2), T(23)), V(T(0.5), T(2.5), T(0)), V(0, 1, 0), T(0.9)};
    return s;
}

/// The kitchen: a room 8 x 3 x 6 with counters along two walls, an island, a table and a
/// partition before a dining corner; 72 disk lights (light_sides-gons, radius 0.09) in a
/// 12 x 6 grid on the ceiling, facing down.
template <Scalar T>
Scene<T> kitchen_scene(int light_sides = 16) {
    Scene<T> s;
    s.name = "kitchen";
    using V = Vec3<T>;
    const auto floor = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.45), T(0.35), T(0.25))));
    const auto wall = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.8), T(0.78), T(0.72))));
    // Lambertian throughout, so that Cycles renders exactly this scene (tools/peer_cycles.py:
    // its Phong lobe is not glint's).
    const auto wood = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.4), T(0.25), T(0.12))));
    const auto white = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.85))));
    const auto light = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.8)), Rgb<T>(T(14), T(12.5), T(10))));
    detail::add_room(s, V(-4, 0, -3), V(4, 3, 3), floor, wall, wall);
    detail::add_block(s, V(-4, 0, -3), V(T(1.5), T(0.9), T(-2.4)), white);     // back counter
    detail::add_block(s, V(-4, T(1.6), -3), V(T(1.5), T(2.4), T(-2.65)), white);  // wall cabinets
    detail::add_block(s, V(-4, 0, T(-2.4)), V(T(-3.4), T(0.9), T(1)), white);     // side counter
    detail::add_block(s, V(T(-1.8), 0, T(-0.6)), V(T(0.2), T(0.92), T(0.4)), wood);  // island
    detail::add_block(s, V(T(1.6), 0, T(-3)), V(T(1.75), T(2.2), T(0.5)), wall);    // partition
    detail::add_block(s, V(T(2.3), T(0.72), T(-1.5)), V(T(3.6), T(0.76), T(0.3)), wood);  // table top
    for (int i = 0; i < 4; ++i)                                                        // table legs
        detail::add_block(s, V(T(i & 1 ? 3.5 : 2.35), 0, T(i & 2 ? 0.2 : -1.45)),
                          V(T(i & 1 ? 3.55 : 2.4), T(0.72), T(i & 2 ? 0.25 : -1.4)), wood);
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 6; ++j) {
            const V c(T(-3.6) + T(0.65) * T(i), T(2.995), T(-2.5) + T(1.0) * T(j));
            const auto disk = detail::ngon(c, T(0.09), light_sides, true);
            s.add_polygon(std::span<const V>(disk), light);
        }
    s.camera = Camera<T>{V(T(3.7), T(1.7), T(2.8)), V(T(-1.2), T(0.9), T(-1.2)), V(0, 1, 0), T(0.95)};
    return s;
}

/// The hall for LIE: a room 20 x 6 x 20, a light_grid x light_grid grid of point lights at
/// 5.6 m (10 x 10), a 5 x 5 grid of pillars (pillar_sides-gons, pillar_rings quads high) and
/// low walls and screens between them.
template <Scalar T>
Scene<T> lie_hall_scene(int pillar_sides = 8, int pillar_rings = 1, int light_grid = 10) {
    Scene<T> s;
    s.name = "lie-hall";
    using V = Vec3<T>;
    const auto floor = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.5))));
    const auto wall = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.65), T(0.62), T(0.6))));
    const auto stone = s.add_material(Material<T>::lambertian(Rgb<T>(T(0.6), T(0.55), T(0.5))));
    detail::add_room(s, V(-10, 0, -10), V(10, 6, 10), floor, wall, wall);
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j) {
            const V c(T(-8) + T(4) * T(i), 0, T(-8) + T(4) * T(j));
            const auto base = detail::ngon(c, T(0.4), pillar_sides);
            detail::add_extrusion(s, std::span<const V>(base), T(6), stone, pillar_rings);
            const V o = c + V(2, 0, 2);
            if ((i + j) % 2 == 0 && i < 4 && j < 4) detail::add_block(s, o - V(T(1.2), 0, T(0.1)), o + V(T(1.2), T(1.4), T(0.1)), stone);
            else if (i < 4 && j < 4) detail::add_block(s, o - V(T(0.1), 0, T(1.1)), o + V(T(0.1), T(3.2), T(1.1)), wall);
        }
    const T step = T(20) / T(light_grid);
    for (int i = 0; i < light_grid; ++i)
        for (int j = 0; j < light_grid; ++j)
            s.point_lights.push_back(PointLight<T>::isotropic(V(T(-10) + step * (T(i) + T(0.5)), T(5.6), T(-10) + step * (T(j) + T(0.5))),
                                                              detail::tint<T>(i * light_grid + j) * T(0.7)));
    s.camera = Camera<T>{V(T(9), T(3.5), T(9.5)), V(T(-2), T(1), T(-2)), V(0, 1, 0), T(0.9)};
    return s;
}

}  // namespace glint
