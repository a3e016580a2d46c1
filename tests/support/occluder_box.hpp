// tests/support/occluder_box.hpp: the box scene of the occluder-sphere measurements (a fixture
// of tests and benchmarks, not part of the library): an object standing in a Cornell-like box,
// rendered with the VPL integrator (glint/vpl/integrator.hpp) to compare visibility policies.
#pragma once

#include <span>

#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// The box [-1, 1]^3: white floor, ceiling and back wall, red left and green right wall, open
/// at +z (closed by a white front wall when `closed`), lit by a square light of half-width 0.3
/// facing down just under the ceiling (radiance `light`); `object` (may be empty) is added as
/// one Lambertian material. The camera looks from +z at the origin.
inline Scene<float> occluder_box(std::span<const TriangleVertices<float>> object, const Rgb<float>& light, bool closed) {
    Scene<float> s;
    s.name = "occluder-box";
    const auto white = s.add_material(Material<float>::lambertian(Rgb<float>(0.75f, 0.75f, 0.75f)));
    const auto red = s.add_material(Material<float>::lambertian(Rgb<float>(0.7f, 0.15f, 0.12f)));
    const auto green = s.add_material(Material<float>::lambertian(Rgb<float>(0.15f, 0.6f, 0.15f)));
    const auto lamp = s.add_material(Material<float>::lambertian(Rgb<float>(0.0f), light));
    using V = Vec3<float>;
    s.add_quad(V(-1, -1, -1), V(1, -1, -1), V(1, -1, 1), V(-1, -1, 1), white);  // floor
    s.add_quad(V(-1, 1, -1), V(-1, 1, 1), V(1, 1, 1), V(1, 1, -1), white);      // ceiling
    s.add_quad(V(-1, -1, -1), V(-1, 1, -1), V(1, 1, -1), V(1, -1, -1), white);  // back
    s.add_quad(V(-1, -1, -1), V(-1, -1, 1), V(-1, 1, 1), V(-1, 1, -1), red);    // left
    s.add_quad(V(1, -1, -1), V(1, 1, -1), V(1, 1, 1), V(1, -1, 1), green);      // right
    if (closed) s.add_quad(V(-1, -1, 1), V(1, -1, 1), V(1, 1, 1), V(-1, 1, 1), white);
    const float l = 0.3f, y = 0.999f;
    s.add_quad(V(-l, y, -l), V(l, y, -l), V(l, y, l), V(-l, y, l), lamp);
    const auto grey = s.add_material(Material<float>::lambertian(Rgb<float>(0.7f, 0.7f, 0.65f)));
    for (const auto& t : object) {
        s.triangles.push_back(t);
        s.material_of.push_back(grey);
        s.light_of.push_back(-1);
    }
    s.camera.eye = V(0, 0, 3.4f);
    s.camera.target = V(0, 0, 0);
    s.camera.fov_y = 0.68f;
    return s;
}

}  // namespace glint
