// glint/core/camera.hpp: a pinhole camera, the rays through film positions (eye, target,
// up vector and vertical field of view, as in pbrt-v4's perspective camera: Pharr, Jakob,
// Humphreys 2023, section 5.2).
#pragma once

#include <cmath>

#include <glint/core/aabb.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>

namespace glint {

/// Pinhole camera: `fov_y` is the full vertical field of view in radians.
template <Scalar T>
struct Camera {
    /// Centre of projection, in world space (default: 5 units along +z).
    Vec3<T> eye{0, 0, 5};
    /// World-space point the camera looks at; the view direction is target - eye (default: the origin).
    Vec3<T> target{0};
    /// World-space up direction; need not be unit or orthogonal to the view direction. If
    /// parallel to it, the film's horizontal axis falls back to +x.
    Vec3<T> up{0, 1, 0};
    /// Full vertical field of view in radians, in (0, pi) (default 0.7, about 40 degrees).
    T fov_y = T(0.7);

    /// Ray through film position (sx, sy) in [0,1]^2, (0,0) at the top left.
    Ray<T> ray(T sx, T sy, T aspect) const {
        const Vec3<T> w = safe_normalize(target - eye);
        const Vec3<T> u = safe_normalize(glm::cross(w, up), Vec3<T>(1, 0, 0));
        const Vec3<T> v = glm::cross(u, w);
        const T h = std::tan(fov_y * T(0.5));
        const Vec3<T> d = w + u * ((T(2) * sx - T(1)) * h * aspect) + v * ((T(1) - T(2) * sy) * h);
        return Ray<T>{eye, safe_normalize(d), T(0), infinity<T>};
    }
};

/// A camera that frames `box`: looking at its centre from the front (+z) and a little above
/// (+y), 2.6 times its half diagonal away, with a 0.7 rad vertical field of view, so that the
/// whole box is in view for any aspect ratio of at least 1. An empty box gives the default camera.
template <Scalar T>
Camera<T> frame_box(const AABB<T>& box) {
    if (box.empty()) return Camera<T>{};
    const Vec3<T> c = box.center();
    const T r = glm::length(box.extent()) * T(0.5);
    return Camera<T>{c + Vec3<T>(T(0), T(0.3), T(1)) * (r * T(2.6)), c, Vec3<T>(0, 1, 0), T(0.7)};
}

}  // namespace glint
