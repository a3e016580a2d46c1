// glint/vpl/scenes.hpp: scenes for the light-animation experiments of Szécsi 2009, ch. 7 ("a
// small light source moving in a static scene", section 7.1) built from any Scene: its area
// lights replaced by a point light, and a light track through the scene.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// `s` without its emitting triangles and lights, lit by one point light instead.
template <Scalar T>
Scene<T> with_point_light(const Scene<T>& s, const Vec3<T>& position, const Rgb<T>& intensity) {
    s.validate();
    Scene<T> out;
    out.name = s.name + "-point";
    out.materials = s.materials;
    out.camera = s.camera;
    out.environment = s.environment;
    for (std::size_t i = 0; i < s.triangles.size(); ++i)
        if (s.light_of[i] < 0 && !s.materials[s.material_of[i]].emissive()) {
            out.triangles.push_back(s.triangles[i]);
            out.material_of.push_back(s.material_of[i]);
            out.light_of.push_back(-1);
        }
    out.point_lights.push_back({position, intensity});
    return out;
}

/// `frames` light positions evenly spaced on the segment from a to b (both ends included).
template <Scalar T>
std::vector<Vec3<T>> light_track(const Vec3<T>& a, const Vec3<T>& b, std::size_t frames) {
    if (frames == 0) throw Error("glint::light_track: frames must be positive (got 0)");
    std::vector<Vec3<T>> p;
    for (std::size_t f = 0; f < frames; ++f)
        p.push_back(frames == 1 ? a : a + (b - a) * (T(f) / T(frames - 1)));
    return p;
}

}  // namespace glint
