// tests/support/lie_hall.hpp: a hall of columns lit by many point lights, the fixture of the
// local-illumination-environment tests and measurements (not part of the library; the many-light
// scenes of lights/scenes.hpp replace it where they exist). Laid out as Fernandez 2004, §3.4
// describes the mosque: a row of bright lights down the central aisle, dimmer ones to the sides,
// columns casting shadows on the floor from all of them.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/lights/light.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

namespace detail {
/// A vertical cylinder (no caps) of `sides` x `rings` quads, counter-clockwise from outside.
inline void lie_hall_column(Scene<float>& s, float x, float z, float r, float h, int sides, int rings, std::uint32_t m) {
    auto p = [&](int i, int k) {
        const float a = 2 * pi<float> * float(i) / float(sides);
        return Vec3<float>(x + r * std::cos(a), h * float(k) / float(rings), z - r * std::sin(a));
    };
    for (int i = 0; i < sides; ++i)
        for (int k = 0; k < rings; ++k) s.add_quad(p(i, k), p(i + 1, k), p(i + 1, k + 1), p(i, k + 1), m);
}
}  // namespace detail

/// The hall [-6, 6] x [0, 3.5] x [-22, 2] (floor, ceiling, side and back walls), `rows` x 4
/// columns (cylinders of `sides` x `rings` quads: the scene's polygon count), `lights` isotropic
/// point lights at height 2.9: a tenth of them bright (intensity 6) down the aisle x = 0, the
/// rest dim (intensity 0.6) in four rows beside the columns. The camera stands in the aisle.
inline Scene<float> lie_hall(int lights, int rows, int sides, int rings) {
    using V = Vec3<float>;
    Scene<float> s;
    s.name = "lie-hall";
    const auto wall = s.add_material(Material<float>::lambertian(Rgb<float>(0.7f, 0.66f, 0.6f)));
    const auto floor = s.add_material(Material<float>::glossy(Rgb<float>(0.45f), Rgb<float>(0.2f), 30.0f));
    const auto stone = s.add_material(Material<float>::lambertian(Rgb<float>(0.8f, 0.75f, 0.65f)));
    const float x0 = -6, x1 = 6, z0 = -22, z1 = 2, h = 3.5f;
    s.add_quad(V(x0, 0, z0), V(x0, 0, z1), V(x1, 0, z1), V(x1, 0, z0), floor);
    s.add_quad(V(x0, h, z0), V(x1, h, z0), V(x1, h, z1), V(x0, h, z1), wall);
    s.add_quad(V(x0, 0, z0), V(x1, 0, z0), V(x1, h, z0), V(x0, h, z0), wall);
    s.add_quad(V(x0, 0, z0), V(x0, h, z0), V(x0, h, z1), V(x0, 0, z1), wall);
    s.add_quad(V(x1, 0, z0), V(x1, 0, z1), V(x1, h, z1), V(x1, h, z0), wall);
    const float spacing = 20.0f / float(std::max(rows, 1));
    for (int r = 0; r < rows; ++r)
        for (const float x : {-4.5f, -1.8f, 1.8f, 4.5f})
            detail::lie_hall_column(s, x, -spacing * (float(r) + 0.5f), 0.3f, h, sides, rings, stone);
    const int bright = std::max(1, lights / 10);
    for (int i = 0; i < lights; ++i) {
        if (i < bright) {
            const float z = -20.0f * (float(i) + 0.5f) / float(bright);
            s.point_lights.push_back(PointLight<float>::isotropic(V(0, 2.9f, z), Rgb<float>(6.0f, 5.6f, 5.0f)));
            continue;
        }
        const int k = i - bright, per_row = (lights - bright + 3) / 4;
        const float xs[4] = {-5.3f, -3.1f, 3.1f, 5.3f};
        const float z = -20.0f * (float(k / 4) + 0.5f) / float(per_row);
        s.point_lights.push_back(PointLight<float>::isotropic(V(xs[k % 4], 2.9f, z), Rgb<float>(0.6f, 0.62f, 0.7f)));
    }
    s.camera = Camera<float>{V(0.4f, 1.7f, 1.5f), V(-0.3f, 0.8f, -10.0f), V(0, 1, 0), 1.0f};
    return s;
}

}  // namespace glint
