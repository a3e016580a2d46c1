// glint/trees/brute_force.hpp: the reference accelerator. Every ray is tested against every
// triangle with the intersector's batch kernel; the trees must return the same hits.
// It has the trees' interface (RayAccelerator): closest_hit(ray, hit) and any_hit(ray).
// Queries are const and keep no shared mutable state: they are thread-safe.
#pragma once

#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

#include <glint/core/ray.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// Reference RayAccelerator: tests every ray against every triangle with P's batch kernel,
/// O(triangles) per ray; the trees are checked against its hits.
template <TriangleIntersector P>
class BruteForce {
public:
    using scalar_type = typename P::scalar_type;  ///< float or double, P's precision.
    using T = scalar_type;                        ///< Shorthand for scalar_type.

    /// All triangles in one block, each in the frame it would have alone
    /// (TriangleStore::add_each): one group in the identity frame; with offset frames (IVM)
    /// a group per triangle, so that every record gets the best frame of its own (a
    /// scene-wide frame far from small triangles costs IVM precision).
    explicit BruteForce(std::span<const TriangleVertices<T>> tris) {
        std::vector<std::uint32_t> ids(tris.size());
        std::iota(ids.begin(), ids.end(), 0u);
        all_ = store_.add_each(tris, ids);
    }

    /// Closest hit with t in (ray.tmin, min(ray.tmax, hit.t)); hit.id is the triangle index.
    bool closest_hit(const Ray<T>& ray, StoreHit<T>& hit) const { return store_.closest_hit(all_, ray, hit); }
    /// Whether any triangle is hit with t in (ray.tmin, ray.tmax).
    bool any_hit(const Ray<T>& ray) const { return store_.any_hit(all_, ray); }

    const TriangleStore<P>& store() const { return store_; }  ///< The triangle records (one block).

private:
    TriangleStore<P> store_;
    typename TriangleStore<P>::BlockRef all_;
};

}  // namespace glint
