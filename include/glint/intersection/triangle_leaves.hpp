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
// full, compile-time width), and the frames of its records (frame.hpp: the identity for most
// tests, an origin per group for the IVM, Szécsi 2009, §4.1); what a reference counts (padded
// records, or groups of records sharing a frame) is the frame's business, not the tree's. A
// query's leaf callable is a LeafQuery, made once per query (it maps the hit's record to the
// user's triangle); the tree traverses the query's ray and calls it for the leaves:
//   Ray<T> r = ray_before(ray, hit);
//   StoreHit<T> h = hit;
//   const auto world = leaves.prepare(r);
//   LeafQuery<P, false> leaf(leaves, r, world, h);
//   if (tree.intersect<false>(r, leaf)) hit = leaf.hit();
// A tree over other primitives passes a leaf callable of its own (tests/test_trees.cpp puts
// spheres in a WideBvh's leaves).
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

/// Triangle records of intersector P laid out for tree leaves (see the file comment).
template <TriangleIntersector P>
class TriangleLeaves {
public:
    using T = typename P::scalar_type;  ///< float or double, P's precision.

    /// Appends one leaf of triangles `tris` (non-empty), reported as `ids` (the user's
    /// triangle indices); returns its reference (first, count).
    std::pair<std::uint32_t, std::uint32_t> add(std::span<const TriangleVertices<T>> tris,
                                                std::span<const std::uint32_t> ids) {
        return store_.leaf(store_.add_block(tris, ids, TriangleStore<P>::Padding::batches));
    }

    /// Room for `leaves` leaves of `records` records in all, each leaf's triangles rounded up
    /// to whole batches (detail::padded; a leaf whose triangles need several frame groups
    /// takes more, allocated as it comes).
    void reserve(std::size_t records, std::size_t leaves) { store_.reserve(records, leaves); }

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

    /// The user's triangle index of record `record` (a closest hit's hit.id).
    std::uint32_t id(std::uint32_t record) const { return store_.id(record); }
    /// Record slots (padding included) that testing leaf (first, count) reads.
    std::uint64_t records(std::uint32_t first, std::uint32_t count) const {
        return store_.leaf_records(first, count);
    }
    std::size_t bytes() const { return store_.bytes(); }  ///< Bytes of records, ids and groups (TriangleStore::bytes).
    const TriangleStore<P>& store() const { return store_; }  ///< The padded store behind the leaves.

private:
    TriangleStore<P> store_;
};

/// The ray of a closest-hit query for `hit`: `ray` with tmax_before(ray, hit).
template <class T>
[[gnu::always_inline]] inline Ray<T> ray_before(const Ray<T>& ray, const StoreHit<T>& hit) {
    Ray<T> r = ray;
    r.tmax = tmax_before(ray, hit);
    return r;
}

/// One query's leaf callable over TriangleLeaves<P> (a LeafTest), the one thing the leaves
/// hand a tree, which traverses the query's ray and calls it for the leaves it enters. It
/// tests with the caller's `ray`, `world` = leaves.prepare(ray) and `hit`, locals of the
/// query that the compiler keeps in registers (a query owning copies of them made GCC copy
/// the ray through the stack; docs/history/trees.md). Any = false: closest hit with t in
/// (ray.tmin, ray.tmax), lowering ray.tmax to each hit found, hit() then being the nearest
/// hit with the user's triangle index. Any = true: whether any triangle is hit.
template <TriangleIntersector P, bool Any>
class LeafQuery {
public:
    using T = typename P::scalar_type;  ///< float or double, P's precision.

    /// Refers to (does not copy) the query's locals: all four must outlive the query.
    [[gnu::always_inline]] LeafQuery(const TriangleLeaves<P>& leaves, Ray<T>& ray, const RayDataOf<P>& world,
                                     StoreHit<T>& hit)
        : leaves_(leaves), ray_(ray), world_(world), hit_(hit) {}
    /// Tests leaf (first, count); true when it holds a hit.
    [[gnu::always_inline]] bool operator()(std::uint32_t first, std::uint32_t count) {
        return leaves_.template test<Any>(first, count, ray_, world_, hit_);
    }
    /// The nearest hit found (closest hit, after a traversal that found one).
    StoreHit<T> hit() const {
        StoreHit<T> h = hit_;
        h.id = leaves_.id(hit_.id);  // the leaf test reports the record
        return h;
    }

private:
    const TriangleLeaves<P>& leaves_;
    Ray<T>& ray_;
    const RayDataOf<P>& world_;
    StoreHit<T>& hit_;
};

}  // namespace glint
