// glint/cones/glass.hpp: the shader of the refraction passes of Szécsi 2009: a ray that hits the glass
// continues as its refracted ray, or as its reflected ray under total internal reflection;
// a ray that misses ends (and reads the environment map, Szécsi 2009, §6.3 and §6.4).
//
// Szécsi 2009, §6.3: "the pixel shader performing the intersection tests
// outputs the refracted ray", and section 6.4 also computes a refracted
// direction for every hit. Snell's law with the geometric normal of the hit triangle: with
// unit direction d, unit normal n facing the incoming ray (d . n < 0) and eta = n_from / n_to,
//     k = 1 - eta^2 (1 - (d . n)^2);  refracted = eta d - (eta (d . n) + sqrt(k)) n  (k >= 0),
//     reflected = d - 2 (d . n) n  (k < 0: total internal reflection).
// The next segment starts at the hit point with tmin = `offset` (world units, the rays are
// unit length) so that it does not hit its own triangle again.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glint/core/math.hpp>
#include <glint/core/optics.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

/// Refraction of the unit direction d at a surface with unit normal n (either side) from
/// index `ior_outside` (the side n points to) into `ior_inside`; total internal reflection
/// gives the mirror direction. Returns whether the ray was refracted.
template <Scalar T>
bool refract_or_reflect(const Vec3<T>& d, const Vec3<T>& n, T ior_outside, T ior_inside, Vec3<T>& out) {
    const bool leaving = glm::dot(d, n) > T(0);
    const Vec3<T> nn = leaving ? -n : n;  // facing the ray
    const T eta = leaving ? ior_inside / ior_outside : ior_outside / ior_inside;
    Vec3<T> refracted;
    if (refract(d, nn, eta, refracted) < T(0)) {
        out = safe_normalize(d - T(2) * glm::dot(d, nn) * nn, d);
        return false;
    }
    out = safe_normalize(refracted, d);
    return true;
}

/// Glass shader for trace_passes: geometric normals per triangle (built once), index of
/// refraction `ior` inside the mesh, 1 outside.
template <Scalar T>
class GlassShader {
public:
    /// Unit geometric normals of `tris` (computed in double, in their winding; allocates one per
    /// triangle), glass of index `ior` (> 0), and next segments starting at tmin = `offset`.
    GlassShader(std::span<const TriangleVertices<T>> tris, T ior, T offset) : ior_(ior), offset_(offset) {
        normals_.reserve(tris.size());
        for (const auto& t : tris)
            normals_.push_back(Vec3<T>(safe_normalize(glm::cross(Vec3d(t[1]) - Vec3d(t[0]), Vec3d(t[2]) - Vec3d(t[0])))));
    }

    /// Replaces `ray` by its next segment; false (path ends) when it found no hit.
    bool operator()(std::size_t, Ray<T>& ray, const StoreHit<T>& hit, bool found) const {
        if (!found) return false;
        const Vec3<T> d = safe_normalize(ray.direction);
        Vec3<T> next;
        refract_or_reflect(d, normals_[hit.id], T(1), ior_, next);
        ray.origin = ray.at(hit.t);
        ray.direction = next;
        ray.tmin = offset_;
        ray.tmax = infinity<T>;
        return true;
    }

    /// Unit geometric normal of triangle `id` (< the number of triangles given).
    const Vec3<T>& normal(std::uint32_t id) const { return normals_[id]; }

private:
    std::vector<Vec3<T>> normals_;
    T ior_, offset_;
};

}  // namespace glint
