// glint/intersection/triangle_leaves.hpp: the leaf storage of every triangle tree, the one
// seam between a tree and a ray-triangle test.
//
// A tree (kd-tree, BIH, wide BVH) knows its leaves only as a reference (first, count) of
// two integers it stores in its nodes, and tests a leaf by calling a leaf callable
// `leaf(first, count)` that returns whether the leaf holds a hit; for closest-hit queries
// the callable lowers the ray's tmax to the hit, so the tree culls by it (madmann91/bvh
// v2's `intersect(ray, ..., leaf_fn)` works the same way). TriangleLeaves<P> is that
// storage for triangles of intersector P: it owns the records (a TriangleStore<P>), their
// padding to whole batches of batch_width records (so a leaf runs P's batch kernel at its
// full, compile-time width), and the frames of its records
// (frame.hpp: the identity for most tests, an origin per group for the IVM, Szécsi 2009, §4.1); what
// a reference counts (padded records, or groups of records sharing a frame) is the frame's
// business, not the tree's. A tree's leaf callable is
// `[&](first, count) { return leaves.test<Any>(first, count, ray, world, hit); }` with
// world = leaves.prepare(ray), made once per query; closest_hit() and any_hit() write that
// wrapper once for every tree, taking the tree's traversal as a callable
// `traverse(ray, leaf)` (a TreeTraversal). A tree over other primitives passes a leaf
// callable of its own (tests/test_trees.cpp puts spheres in a WideBvh's leaves).
//
// Thread safety: leaf tests are const and keep their state in the caller's callable.
#pragma once

#include <concepts>
#include <cstdint>
#include <span>
#include <utility>

#include <glint/core/ray.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

/// A leaf callable: `leaf(first, count)` tests the leaf (first, count) and returns whether it
/// found a hit (closest-hit queries: a hit nearer than the ray's tmax, to which it lowers the
/// ray's tmax).
template <class F>
concept LeafTest = requires(F f, std::uint32_t i) {
    { f(i, i) } -> std::convertible_to<bool>;
};

namespace detail {
/// The leaf callable type a TreeTraversal is checked with (its stand-in for a real one).
using LeafProbe = bool (*)(std::uint32_t, std::uint32_t);
}  // namespace detail

/// A tree's traversal as TriangleLeaves' queries take it: `traverse(ray, leaf)` runs the tree
/// over `ray` (a Ray<T>&, whose tmax the leaf callable lowers), calling the LeafTest `leaf`
/// for the leaves the ray enters, and returns whether any call returned true.
template <class F, class T>
concept TreeTraversal = requires(F f, Ray<T>& r, detail::LeafProbe leaf) {
    { f(r, leaf) } -> std::convertible_to<bool>;
};

/// Triangle records of intersector P laid out for tree leaves (see the file comment).
template <TriangleIntersector P>
class TriangleLeaves {
public:
    using T = typename P::scalar_type;

    /// Appends one leaf of triangles `tris` (non-empty), reported as `ids` (the user's
    /// triangle indices); returns its reference (first, count).
    std::pair<std::uint32_t, std::uint32_t> add(std::span<const TriangleVertices<T>> tris,
                                                std::span<const std::uint32_t> ids) {
        return store_.leaf(store_.add_block(tris, ids, TriangleStore<P>::Padding::batches));
    }

    /// The per-query ray data of test(): P's prepared ray in the world frame (with offset
    /// frames, the leaf prepares the ray again per group).
    RayDataOf<P> prepare(const Ray<T>& ray) const { return P::prepare(ray); }
    /// Tests leaf (first, count) with the interval (ray.tmin, ray.tmax); `world` is
    /// prepare(ray) of the query. For closest hit (Any = false) keeps the nearest hit in
    /// `hit` (hit.id is then a record index: map it with id()) and lowers ray.tmax to it;
    /// ray.tmax must not exceed hit.t. True when the leaf holds a hit.
    template <bool Any>
    [[gnu::always_inline]] bool test(std::uint32_t first, std::uint32_t count, Ray<T>& ray,
                                     const RayDataOf<P>& world, StoreHit<T>& hit) const {
        if (!store_.template test_leaf<Any>(first, count, ray, world, hit)) return false;
        if constexpr (!Any) ray.tmax = hit.t;
        return true;
    }

    /// Closest hit with t in (ray.tmin, min(ray.tmax, hit.t)) through a tree's traversal
    /// (`traverse(r, leaf)`, a TreeTraversal); true when `hit` was updated, hit.id then being
    /// the user's triangle index. With `record_count`, adds the record slots tested to it.
    template <class Traverse>
        requires TreeTraversal<Traverse, T>
    [[gnu::always_inline]] bool closest_hit(const Ray<T>& ray, StoreHit<T>& hit, Traverse&& traverse,
                                            std::uint64_t* record_count = nullptr) const {
        // On local copies: the compiler keeps them in registers (the caller's `hit` could
        // alias the traversal stack's floats).
        StoreHit<T> h = hit;
        Ray<T> r = ray;
        r.tmax = hit.t < ray.tmax ? hit.t : ray.tmax;  // keeps a NaN tmax (no hit)
        const auto world = prepare(r);
        if (!traverse(r, [&](std::uint32_t first, std::uint32_t count) {
                if (record_count) *record_count += records(first, count);
                return test<false>(first, count, r, world, h);
            }))
            return false;
        hit = h;
        hit.id = id(h.id);  // the leaf test reports the record
        return true;
    }
    /// Whether any triangle is hit with t in (ray.tmin, ray.tmax) (shadow rays), through a
    /// tree's traversal as in closest_hit().
    template <class Traverse>
        requires TreeTraversal<Traverse, T>
    [[gnu::always_inline]] bool any_hit(const Ray<T>& ray, Traverse&& traverse) const {
        StoreHit<T> h;
        Ray<T> r = ray;
        const auto world = prepare(r);
        return traverse(r, [&](std::uint32_t first, std::uint32_t count) {
            return test<true>(first, count, r, world, h);
        });
    }

    /// The user's triangle index of record `record` (a closest hit's hit.id).
    std::uint32_t id(std::uint32_t record) const { return store_.id(record); }
    /// Record slots (padding included) that testing leaf (first, count) reads.
    std::uint64_t records(std::uint32_t first, std::uint32_t count) const {
        return store_.leaf_records(first, count);
    }
    std::size_t bytes() const { return store_.bytes(); }
    const TriangleStore<P>& store() const { return store_; }

private:
    TriangleStore<P> store_;
};

}  // namespace glint
