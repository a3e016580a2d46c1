// glint/photons/surface_groups.hpp: several photon maps, one per surface group (Larsen 2004,
// ch. 8). Triangles are grouped across shared edges whose dihedral angle (the angle between
// the two triangles' normals, 0 for coplanar neighbours) is below alpha; each group gets its
// own photon map, and a lookup searches only the map of the surface it is on. The maps are
// smaller (balancing is O(n log n), a query visits fewer nodes), they balance in parallel,
// and light no longer leaks through corners: a point on one wall never gathers photons from
// the wall meeting it at a right angle when alpha < 90 degrees.
//
// Edges are shared when their two end points are equal coordinate for coordinate (meshes
// that share vertices); normals come from the vertex order, so a mesh must be consistently
// oriented for its smooth parts to group.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/parallel.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/photons/photon.hpp>
#include <glint/photons/photon_map.hpp>

namespace glint {

/// The group of every triangle (0 .. count - 1).
struct SurfaceGroups {
    std::vector<std::uint32_t> group_of;  ///< Group of each scene triangle, indexed like Scene::triangles.
    std::size_t count = 0;                ///< Number of groups.
};

namespace detail {

/// Union-find root of i with path halving.
inline std::uint32_t group_root(std::vector<std::uint32_t>& parent, std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

}  // namespace detail

/// Groups `triangles` across shared edges whose dihedral angle is below `alpha` (radians).
template <Scalar T>
SurfaceGroups surface_groups(std::span<const TriangleVertices<T>> triangles, T alpha) {
    if (!(alpha >= T(0)) || !(alpha <= pi<T>))
        throw Error("glint::surface_groups: alpha must be in [0, pi] radians (got " + std::to_string(alpha) + ")");
    struct Edge {
        std::array<T, 6> key;  // the two end points, lexicographically ordered
        std::uint32_t triangle;
    };
    std::vector<Edge> edges;
    edges.reserve(triangles.size() * 3);
    std::vector<Vec3<T>> normals(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const auto& t = triangles[i];
        normals[i] = safe_normalize(glm::cross(t[1] - t[0], t[2] - t[0]));
        for (int e = 0; e < 3; ++e) {
            std::array<T, 3> a{t[e].x, t[e].y, t[e].z}, b{t[(e + 1) % 3].x, t[(e + 1) % 3].y, t[(e + 1) % 3].z};
            if (b < a) std::swap(a, b);
            edges.push_back({{a[0], a[1], a[2], b[0], b[1], b[2]}, std::uint32_t(i)});
        }
    }
    std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return x.key < y.key; });
    std::vector<std::uint32_t> parent(triangles.size());
    std::iota(parent.begin(), parent.end(), 0u);
    const T cos_alpha = std::cos(alpha);
    for (std::size_t lo = 0, hi; lo < edges.size(); lo = hi) {
        for (hi = lo + 1; hi < edges.size() && edges[hi].key == edges[lo].key; ++hi) {}
        for (std::size_t a = lo; a < hi; ++a)
            for (std::size_t b = a + 1; b < hi; ++b) {
                const std::uint32_t i = edges[a].triangle, j = edges[b].triangle;
                if (glm::dot(normals[i], normals[j]) > cos_alpha)  // angle between normals < alpha
                    parent[detail::group_root(parent, i)] = detail::group_root(parent, j);
            }
    }
    SurfaceGroups g;
    g.group_of.assign(triangles.size(), ~0u);
    std::vector<std::uint32_t> id_of_root(triangles.size(), ~0u);
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const std::uint32_t r = detail::group_root(parent, std::uint32_t(i));
        if (id_of_root[r] == ~0u) id_of_root[r] = std::uint32_t(g.count++);
        g.group_of[i] = id_of_root[r];
    }
    return g;
}

/// One PhotonMap per surface group, balanced in parallel.
class GroupedPhotonMaps {
public:
    GroupedPhotonMaps() = default;
    /// photons[i] lies on triangle triangle_of[i]; threads 0: hardware concurrency.
    GroupedPhotonMaps(std::span<const Photon> photons, std::span<const std::uint32_t> triangle_of,
                      const SurfaceGroups& groups, int threads = 0)
        : group_of_(groups.group_of), maps_(groups.count) {
        if (triangle_of.size() != photons.size())
            throw Error("glint::GroupedPhotonMaps: " + std::to_string(photons.size()) + " photons but " +
                        std::to_string(triangle_of.size()) + " triangle indices");
        std::vector<std::vector<Photon>> parts(groups.count);
        for (std::size_t i = 0; i < photons.size(); ++i) {
            if (triangle_of[i] >= group_of_.size())
                throw Error("glint::GroupedPhotonMaps: photon " + std::to_string(i) + " lies on triangle " +
                            std::to_string(triangle_of[i]) + ", beyond the " + std::to_string(group_of_.size()) + " grouped");
            parts[group_of_[triangle_of[i]]].push_back(photons[i]);
        }
        build(parts, threads);
    }

    /// Maps already split by group (parts[g]: the photons of group g, moved from), for callers
    /// that group photons themselves; group_of: the group of every triangle.
    GroupedPhotonMaps(std::vector<std::vector<Photon>>& parts, std::vector<std::uint32_t> group_of, int threads = 0)
        : group_of_(std::move(group_of)), maps_(parts.size()) {
        build(parts, threads);
    }

    /// Number of surface groups, one map each.
    std::size_t groups() const { return maps_.size(); }
    /// The map of group g (unchecked: g < groups()).
    const PhotonMap& group(std::size_t g) const { return maps_[g]; }
    /// The map of the surface group that triangle `triangle` belongs to.
    const PhotonMap& map_of_triangle(std::uint32_t triangle) const { return maps_[group_of_[triangle]]; }

private:
    void build(std::vector<std::vector<Photon>>& parts, int threads) {
        // Largest groups first, so that one big group does not start last.
        std::vector<std::uint32_t> order(parts.size());
        std::iota(order.begin(), order.end(), 0u);
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return parts[a].size() > parts[b].size(); });
        detail::parallel_blocks(int(order.size()), threads, [&](std::atomic<int>& next) {
            for (int j = next++; j < int(order.size()); j = next++) maps_[order[std::size_t(j)]] = PhotonMap(std::move(parts[order[std::size_t(j)]]));
        });
    }

    std::vector<std::uint32_t> group_of_;
    std::vector<PhotonMap> maps_;
};

}  // namespace glint
