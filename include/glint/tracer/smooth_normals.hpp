// glint/tracer/smooth_normals.hpp: corner normals for a scene whose meshes have none (an OBJ
// without `vn`, a scanned mesh), so that the path tracer shades it smoothly (Scene::
// shading_normal).
//
// Each triangle corner gets the mean of the unit geometric normals of the triangles that
// share its position, each weighted by that triangle's angle at the position (Thürmer and
// Wüthrich 1998: the result does not depend on how the faces around the vertex are
// triangulated), over only the triangles whose normal lies within the crease angle of the
// corner's own triangle: edges sharper than the crease stay sharp. Positions are shared when
// their coordinates are equal (a triangle soup's copies of a vertex), not when merely close.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

namespace detail {

/// A position's coordinates as a hash key (-0 taken as +0, so that equal values are one key).
template <Scalar T>
struct CornerKey {
    std::array<T, 3> p;
    explicit CornerKey(const Vec3<T>& v) : p{v.x + T(0), v.y + T(0), v.z + T(0)} {}
    bool operator==(const CornerKey&) const = default;
};

template <Scalar T>
struct CornerKeyHash {
    std::size_t operator()(const CornerKey<T>& k) const {
        std::uint64_t h = 0x9E3779B97F4A7C15ull;
        for (T c : k.p) {
            std::uint64_t bits = 0;
            std::memcpy(&bits, &c, sizeof(T));
            h = (h ^ bits) * 0xBF58476D1CE4E5B9ull;
            h ^= h >> 31;
        }
        return std::size_t(h);
    }
};

/// Triangle t's interior angle at corner k (0 for a degenerate corner).
template <Scalar T>
T corner_angle(const TriangleVertices<T>& t, int k) {
    const Vec3<T> a = safe_normalize(t[std::size_t((k + 1) % 3)] - t[std::size_t(k)], Vec3<T>(0));
    const Vec3<T> b = safe_normalize(t[std::size_t((k + 2) % 3)] - t[std::size_t(k)], Vec3<T>(0));
    return std::acos(std::clamp(glm::dot(a, b), T(-1), T(1)));
}

}  // namespace detail

/// Sets s.corner_normals (replacing any) as the file comment says, with edges whose faces
/// meet at more than `crease_degrees` (in [0, 180]) kept sharp; throws glint::Error for a
/// crease angle outside that range.
template <Scalar T>
void smooth_corner_normals(Scene<T>& s, T crease_degrees) {
    if (!(crease_degrees >= T(0) && crease_degrees <= T(180)))
        throw Error("smooth_corner_normals: crease angle " + std::to_string(crease_degrees) + " is not in [0, 180] degrees");
    const T cos_crease = std::cos(crease_degrees * pi<T> / T(180)) - T(1e-6);  // 0 degrees: coplanar faces still meet
    std::vector<Vec3<T>> n(s.triangles.size());
    std::unordered_map<detail::CornerKey<T>, std::vector<std::uint32_t>, detail::CornerKeyHash<T>> corners;
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
        n[t] = s.normal(t);
        for (int k = 0; k < 3; ++k) corners[detail::CornerKey<T>(s.triangles[t][std::size_t(k)])].push_back(std::uint32_t(3 * t + std::size_t(k)));
    }
    s.corner_normals.assign(s.triangles.size(), {});
    for (const auto& [key, at] : corners)
        for (std::uint32_t c : at) {
            const std::size_t t = c / 3;
            Vec3<T> sum(0);
            for (std::uint32_t o : at)
                if (glm::dot(n[o / 3], n[t]) >= cos_crease)
                    sum += n[o / 3] * detail::corner_angle(s.triangles[o / 3], int(o % 3));
            s.corner_normals[t][c % 3] = safe_normalize(sum, n[t]);
        }
}

}  // namespace glint
