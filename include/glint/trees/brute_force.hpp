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

template <TriangleIntersector P>
class BruteForce {
public:
    using scalar_type = typename P::scalar_type;
    using T = scalar_type;

    /// All triangles in one block of the store; for intersectors whose records live in a
    /// frame (IVM), one block per triangle, so that every record gets the best frame of its
    /// own (a scene-wide frame far from small triangles costs IVM precision). The blocks'
    /// groups are consecutive, so one BlockRef spans them all.
    explicit BruteForce(std::span<const TriangleVertices<T>> tris) {
        std::vector<std::uint32_t> ids(tris.size());
        std::iota(ids.begin(), ids.end(), 0u);
        if constexpr (P::uses_frame) {
            for (std::size_t i = 0; i < tris.size(); ++i) store_.add_block(tris.subspan(i, 1), std::span(ids).subspan(i, 1));
            all_ = {0, static_cast<std::uint32_t>(store_.group_count())};
        } else {
            all_ = store_.add_block(tris, ids);
        }
    }

    /// Closest hit with t in (ray.tmin, min(ray.tmax, hit.t)); hit.id is the triangle index.
    bool closest_hit(const Ray<T>& ray, StoreHit<T>& hit) const { return store_.closest_hit(all_, ray, hit); }
    /// Whether any triangle is hit with t in (ray.tmin, ray.tmax).
    bool any_hit(const Ray<T>& ray) const { return store_.any_hit(all_, ray); }

    const TriangleStore<P>& store() const { return store_; }

private:
    TriangleStore<P> store_;
    typename TriangleStore<P>::BlockRef all_;
};

}  // namespace glint
