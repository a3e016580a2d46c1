// glint/trees/mesh_bvh.hpp: glint's fast ray accelerator, a wide BVH (wide_bvh.hpp) over a
// triangle mesh, read from the user's own arrays.
//
//   const glint::IndexedMesh<float> mesh{positions, vertex_count, stride_bytes, indices, triangle_count};
//   const glint::MeshBvh<> bvh(mesh, {.threads = 2});  // Möller-Trumbore, 8 wide: the fastest
//   glint::StoreHit<float> hit;  // hit.id: the index of the user's triangle
//   if (bvh.closest_hit(ray, hit)) n = mesh.geometric_normal(hit.id);  // core/offset.hpp
//   bvh.closest_hit(rays, hits);  // spans of rays and hits: packets of 16 where coherent (wide_packet.hpp)
// Leaves are TriangleLeaves<P> (padded to whole batches of 8 records, tested with the
// intersector's batch kernel through the leaf callable, a LeafQuery, WideBvh::intersect takes), laid out
// in the order traversal meets the nodes.
// The mesh is read only while building; the accelerator keeps its own records and nothing
// else per triangle: a hit's geometric normal comes from the user's mesh
// (IndexedMesh::geometric_normal(hit.id), or geometric_normal(tris[hit.id]) for a soup).
// With BvhBuildOptions::spatial_splits (bvh_builder.hpp) a triangle may have a record in
// several leaves; hits still report the user's triangle index.
// Queries are const and keep no shared mutable state: they are thread-safe.
#pragma once

#include <algorithm>
#include <bit>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/offset.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/intersection/triangle_leaves.hpp>
#include <glint/trees/bvh_builder.hpp>
#include <glint/trees/tree.hpp>
#include <glint/trees/packet_leaf.hpp>
#include <glint/trees/wide_bvh.hpp>
#include <glint/trees/wide_packet.hpp>

namespace glint {

/// A triangle mesh in the user's arrays: vertex i's x, y, z are the three T at byte offset
/// i * stride_bytes of `positions`; triangle j is vertices indices[3j], [3j+1], [3j+2].
template <Scalar T>
struct IndexedMesh {
    const void* positions = nullptr;           ///< The first vertex's x (the user's array, not copied).
    std::size_t vertex_count = 0;              ///< Vertices in `positions`.
    std::size_t stride_bytes = 3 * sizeof(T);  ///< Bytes from one vertex to the next.
    const std::uint32_t* indices = nullptr;    ///< 3 * triangle_count vertex indices.
    std::size_t triangle_count = 0;            ///< Triangles in `indices`.

    /// Vertex i (unchecked: check() validates the indices once).
    Vec3<T> vertex(std::uint32_t i) const {
        T p[3];
        std::memcpy(p, static_cast<const char*>(positions) + std::size_t(i) * stride_bytes, sizeof p);
        return {p[0], p[1], p[2]};
    }
    /// Triangle j's three vertices.
    TriangleVertices<T> triangle(std::size_t j) const {
        return {vertex(indices[3 * j]), vertex(indices[3 * j + 1]), vertex(indices[3 * j + 2])};
    }
    /// Triangle j's unit geometric normal in its winding (core/offset.hpp): a hit's, by hit.id.
    Vec3<T> geometric_normal(std::size_t j) const { return glint::geometric_normal(triangle(j)); }
    /// Throws glint::Error naming the first bad field, triangle or index.
    void check() const {
        if (triangle_count > 0 && (!positions || !indices))
            throw Error("IndexedMesh: " + std::to_string(triangle_count) + " triangles but no " +
                        (positions ? "indices" : "positions"));
        if (stride_bytes < 3 * sizeof(T))
            throw Error("IndexedMesh: stride_bytes " + std::to_string(stride_bytes) + " is less than one vertex (" +
                        std::to_string(3 * sizeof(T)) + ")");
        for (std::size_t k = 0; k < 3 * triangle_count; ++k)
            if (indices[k] >= vertex_count)
                throw Error("IndexedMesh: triangle " + std::to_string(k / 3) + " has vertex index " +
                            std::to_string(indices[k]) + " but there are " + std::to_string(vertex_count) + " vertices");
    }
};

/// Wide BVH (N = 8 or 4 children per node, child boxes stored as B says, nodes arranged by
/// layout policy L) over triangles tested with intersector P. MeshBvh<> is the fastest
/// combination bench_trees measures (Möller-Trumbore records in 8-wide float nodes).
template <TriangleIntersector P = MollerTrumbore<float>, int N = 8, WideBoxes B = WideBoxes::floats, WideNodeLayout L = WideBuildOrder>
    requires std::same_as<typename P::scalar_type, float>
class MeshBvh {
public:
    using scalar_type = float;     ///< Queries take float rays.
    using T = float;               ///< Short for scalar_type.
    using intersector_type = P;    ///< The leaf records' triangle test.

    /// From the user's indexed mesh (hits report the index of the user's triangle).
    explicit MeshBvh(const IndexedMesh<float>& mesh, const BvhBuildOptions& opt = {}) {
        mesh.check();
        build(mesh.triangle_count, [&](std::size_t j) { return mesh.triangle(j); }, opt);
    }
    /// From a triangle soup (hits report the position in `tris`).
    explicit MeshBvh(std::span<const TriangleVertices<float>> tris, const BvhBuildOptions& opt = {}) {
        build(tris.size(), [&](std::size_t j) { return tris[j]; }, opt);
    }

    /// Closest hit with t in (ray.tmin, min(ray.tmax, hit.t)); true when `hit` was updated.
    bool closest_hit(const Ray<float>& ray, StoreHit<float>& hit) const { return closest(ray, hit); }
    /// closest_hit(), counting the nodes, leaves and records it tests into `counters`.
    bool closest_hit(const Ray<float>& ray, StoreHit<float>& hit, WideBvhCounters& counters) const {
        return bvh_.dispatch([&](auto kernels) __attribute__((always_inline)) {
            return closest(kernels, ray, hit, counting(counters), [&] { ++counters.nodes; });
        });
    }
    /// Whether any triangle is hit with t in (ray.tmin, ray.tmax) (shadow rays).
    bool any_hit(const Ray<float>& ray) const {
        return bvh_.dispatch([&](auto kernels) __attribute__((always_inline)) { return any(kernels, ray, uncounted, NoNodeHook{}); });
    }
    /// any_hit(), counting the nodes, leaves and records it tests into `counters`.
    bool any_hit(const Ray<float>& ray, WideBvhCounters& counters) const {
        return bvh_.dispatch([&](auto kernels) __attribute__((always_inline)) {
            return any(kernels, ray, counting(counters), [&] { ++counters.nodes; });
        });
    }

    /// Packets on 8-wide trees (measured, tested); other widths trace streams a ray at a time.
    static constexpr bool packets = N == 8;
    /// Closest hits of a stream of rays: hits[i] as closest_hit(rays[i], hits[i]) gives it
    /// (the same t, u, v and id); returns how many hits were updated. On 8-wide trees consecutive
    /// rays go in packets of 16 sharing the node visits where they are coherent (wide_packet.hpp),
    /// as single rays otherwise. Throws glint::Error naming both sizes when they differ.
    std::size_t closest_hit(std::span<const Ray<float>> rays, std::span<StoreHit<float>> hits) const {
        return closest_stream(rays, hits, uncounted, [](unsigned) {});
    }
    /// The stream closest_hit(), counting into `counters` (nodes: ray-node tests; packets:
    /// node visits of packets).
    std::size_t closest_hit(std::span<const Ray<float>> rays, std::span<StoreHit<float>> hits,
                            WideBvhCounters& counters) const {
        return closest_stream(rays, hits, counting(counters), packet_counting(counters));
    }
    /// Any hits of a stream of rays: occluded[i] = any_hit(rays[i]), in packets as above;
    /// returns how many are occluded. Throws glint::Error naming both sizes when they differ.
    std::size_t any_hit(std::span<const Ray<float>> rays, std::span<bool> occluded) const {
        return any_stream(rays, occluded, uncounted, [](unsigned) {});
    }
    /// The stream any_hit(), counting into `counters` (as the stream closest_hit()).
    std::size_t any_hit(std::span<const Ray<float>> rays, std::span<bool> occluded, WideBvhCounters& counters) const {
        return any_stream(rays, occluded, counting(counters), packet_counting(counters));
    }

    /// The kernels queries run (core/isa.hpp): the best this CPU supports, checked when the
    /// tree is built; set_isa() picks another (the same hits; for tests and comparisons).
    Isa isa() const { return bvh_.isa(); }
    void set_isa(Isa isa) { bvh_.set_isa(isa); }  ///< Runs queries with `isa`'s kernels (one the CPU supports).

    const WideBvh<N, B, L>& bvh() const { return bvh_; }  ///< The wide BVH over the leaves (nodes, stats).
    /// The triangle records of the leaves.
    const TriangleLeaves<P>& leaves() const { return leaves_; }
    /// Node bytes plus triangle-record bytes.
    std::size_t total_bytes() const { return bvh_.stats().node_bytes + leaves_.bytes(); }

private:
    [[gnu::noinline]] bool closest(const Ray<float>& ray, StoreHit<float>& hit) const {
        return bvh_.dispatch([&](auto kernels) __attribute__((always_inline)) {
            return closest(kernels, ray, hit, uncounted, NoNodeHook{});
        });
    }
    /// The queries with kernels I (inside the tree's dispatch); `wrap(leaf)` gives the leaf
    /// test the traversal calls (the leaf itself, or a counting one). On local copies of the
    /// ray and the hit: the compiler keeps them in registers (the caller's `hit` could alias
    /// the traversal stack's floats).
    template <Isa I, class Wrap, class Hook>
    [[gnu::always_inline]] bool closest(IsaTag<I> kernels, const Ray<float>& ray, StoreHit<float>& hit, Wrap&& wrap,
                                        Hook&& node_hook) const {
        Ray<float> r = ray_before(ray, hit);
        StoreHit<float> h = hit;
        const auto world = leaves_.prepare(r);
        LeafQuery<P, false> leaf(leaves_, r, world, h);
        if (!bvh_.template intersect<false>(kernels, r, wrap(leaf), node_hook)) return false;
        hit = leaf.hit();
        return true;
    }
    template <Isa I, class Wrap, class Hook>
    [[gnu::always_inline]] bool any(IsaTag<I> kernels, const Ray<float>& ray, Wrap&& wrap, Hook&& node_hook) const {
        Ray<float> r = ray;
        StoreHit<float> h;
        const auto world = leaves_.prepare(r);
        LeafQuery<P, true> leaf(leaves_, r, world, h);
        return bvh_.template intersect<true>(kernels, r, wrap(leaf), node_hook);
    }
    /// The leaf tests of a query as they are, or counted into `c`.
    static constexpr auto uncounted = [](auto& leaf) -> auto& { return leaf; };
    auto counting(WideBvhCounters& c) const {
        return [this, &c](auto& leaf) {
            return [this, &c, &leaf](std::uint32_t first, std::uint32_t count) {
                ++c.leaves;
                c.records += leaves_.records(first, count);
                return leaf(first, count);
            };
        };
    }

    /// The streams: one dispatch, then `packet(kernels, rays, out, n)` on packets of
    /// packet_lanes rays (the last may be short); returns the sum of what it returns.
    template <class Out, class Packet>
    std::size_t stream(const char* query, std::span<const Ray<float>> rays, std::span<Out> out, Packet&& packet) const {
        detail::check_stream(std::string("MeshBvh::") + query, rays.size(), out.size());
        std::size_t n = 0;
        detail::PacketEntry stack[WideBvh<N, B, L>::max_stack];
        bvh_.dispatch([&](auto kernels) __attribute__((always_inline)) {
            for (std::size_t i = 0; i < rays.size(); i += detail::packet_lanes) {
                const int k = int(std::min<std::size_t>(detail::packet_lanes, rays.size() - i));
                n += packet(kernels, rays.data() + i, out.data() + i, k, stack);
            }
            return true;
        });
        return n;
    }
    template <class Wrap, class Hook>
    std::size_t closest_stream(std::span<const Ray<float>> rays, std::span<StoreHit<float>> hits, Wrap&& wrap,
                               Hook&& hook) const {
        return stream("closest_hit", rays, hits, [&](auto kernels, const Ray<float>* r, StoreHit<float>* h, int k,
                                                      detail::PacketEntry* stack) __attribute__((always_inline)) {
            return closest_packet(kernels, r, h, k, wrap, hook, stack);
        });
    }
    template <class Wrap, class Hook>
    std::size_t any_stream(std::span<const Ray<float>> rays, std::span<bool> occluded, Wrap&& wrap, Hook&& hook) const {
        return stream("any_hit", rays, occluded, [&](auto kernels, const Ray<float>* r, bool* o, int k,
                                                  detail::PacketEntry* stack) __attribute__((always_inline)) {
            return any_packet(kernels, r, o, k, wrap, hook, stack);
        });
    }
    /// One packet of n <= packet_lanes rays: the packet traversal where they are coherent,
    /// single rays otherwise; returns the hits. The single rays are traced in this function's
    /// own loop, not from a lambda that for_sign_groups() calls: in a large unit GCC left such
    /// lambdas out of the kernels' dispatch, compiled for the baseline instruction set (random
    /// rays 0.75-0.78x single rays through the Python module).
    template <Isa I, class Wrap, class Hook>
    [[gnu::always_inline]] int closest_packet(IsaTag<I> kernels, const Ray<float>* rays, StoreHit<float>* hits, int n,
                                              Wrap& wrap, Hook& hook, detail::PacketEntry* stack) const {
        int found = 0;
        const auto one = [&]() __attribute__((always_inline)) { hook(1u); };  // a single ray's node hook
        const auto singles = [&]() __attribute__((always_inline)) {  // single rays (an empty tree: no hits)
            for (int k = 0; k < n; ++k) found += closest(kernels, rays[k], hits[k], wrap, one);
            return found;
        };
        if constexpr (!packets) return singles();
        else if constexpr (detail::packet_leaf_supported<P>) {
            alignas(64) detail::PacketLeafRays p;
            p.load(rays, n, [&](int k) { return tmax_before(rays[k], hits[k]); });
            if (bvh_.nodes().empty()) return singles();
            p.set_bounds(n, [&](int k) { return hits[k].t; });
            unsigned hit = 0;  // packets of the rays with one sign per axis, the others alone
            const auto group = [&](const auto& g) { hit |= packet_leaves<false>(kernels, p, g, wrap, hook, stack); };
            for (unsigned m = detail::for_sign_groups(detail::packet_shape(p, n), n, group); m; m &= m - 1)
                found += closest(kernels, rays[std::countr_zero(m)], hits[std::countr_zero(m)], wrap, one);
            for (unsigned m = hit; m; m &= m - 1, ++found) {
                const int k = std::countr_zero(m);
                hits[k].t = p.t[k], hits[k].u = p.u[k], hits[k].v = p.v[k], hits[k].id = leaves_.id(p.id[k]);
            }
            return found;
        } else {
            Ray<float> r[detail::packet_lanes];
            StoreHit<float> h[detail::packet_lanes];
            RayDataOf<P> world[detail::packet_lanes];
            for (int k = 0; k < n; ++k) r[k] = ray_before(rays[k], hits[k]), h[k] = hits[k];
            const unsigned hit = traverse_packet<false>(kernels, r, h, world, n, wrap, hook, stack);
            if (hit == ~0u) return singles();
            for (unsigned m = hit; m; m &= m - 1, ++found) {
                const int k = std::countr_zero(m);
                hits[k] = LeafQuery<P, false>(leaves_, r[k], world[k], h[k]).hit();
            }
            return found;
        }
    }
    template <Isa I, class Wrap, class Hook>
    [[gnu::always_inline]] int any_packet(IsaTag<I> kernels, const Ray<float>* rays, bool* occluded, int n, Wrap& wrap,
                                          Hook& hook, detail::PacketEntry* stack) const {
        int found = 0;
        const auto one = [&]() __attribute__((always_inline)) { hook(1u); };
        const auto singles = [&]() __attribute__((always_inline)) {
            for (int k = 0; k < n; ++k) found += occluded[k] = any(kernels, rays[k], wrap, one);
            return found;
        };
        if constexpr (!packets) return singles();
        unsigned hit;
        if constexpr (detail::packet_leaf_supported<P>) {
            alignas(64) detail::PacketLeafRays p;
            p.load(rays, n, [&](int k) { return rays[k].tmax; });
            if (bvh_.nodes().empty()) return singles();
            p.set_bounds(n, [](int) { return infinity<float>; });
            hit = 0;  // packets of the rays with one sign per axis, the others alone
            const auto group = [&](const auto& g) { hit |= packet_leaves<true>(kernels, p, g, wrap, hook, stack); };
            for (unsigned m = detail::for_sign_groups(detail::packet_shape(p, n), n, group); m; m &= m - 1)
                hit |= unsigned(any(kernels, rays[std::countr_zero(m)], wrap, one)) << std::countr_zero(m);
        } else {
            Ray<float> r[detail::packet_lanes];
            StoreHit<float> h[detail::packet_lanes];
            RayDataOf<P> world[detail::packet_lanes];
            for (int k = 0; k < n; ++k) r[k] = rays[k];
            hit = traverse_packet<true>(kernels, r, h, world, n, wrap, hook, stack);
            if (hit == ~0u) return singles();
        }
        for (int k = 0; k < n; ++k) found += occluded[k] = (hit >> k) & 1u;
        return found;
    }
    /// The packet traversal of a coherent packet (closest or any hit) with leaves tested by
    /// the whole packet (trees/packet_leaf.hpp; P's ray data is the plain ray, so `p` holds
    /// the rays with their hit bounds); returns the mask of lanes that found a hit, whose
    /// hit is in p (p.id[k]: a record).
    template <bool Any, Isa I, class Wrap, class Hook>
    [[gnu::always_inline]] unsigned packet_leaves(IsaTag<I>, detail::PacketLeafRays& p, const detail::PacketShape& shape,
                                                  Wrap& wrap, Hook& hook, detail::PacketEntry* stack) const {
        const detail::PacketBoxTest<I> box(p, shape);
        const RecordView<P> view = leaves_.store().view();
        auto leaf = [&](unsigned lanes, std::uint32_t first, std::uint32_t count, float* tmax)
                        __attribute__((always_inline)) {
            auto none = [](std::uint32_t, std::uint32_t) { return false; };
            for (unsigned m = lanes; m; m &= m - 1) wrap(none)(first, count);  // counts each lane's leaf
            const unsigned hit = detail::packet_leaf<Any, P>(view, first, count, lanes, p);
            if constexpr (!Any)
                for (unsigned m = hit; m; m &= m - 1) tmax[std::countr_zero(m)] = p.t[std::countr_zero(m)];
            return hit;
        };
        return detail::packet_traverse<Any, N, I>(bvh_.nodes().data(), box, p.tmax, shape.lanes, leaf, hook, stack);
    }
    /// The same for other policies, on rays r[0, n): each lane's leaf test is the single
    /// ray's LeafQuery on r[k], world[k] (prepared here) and h[k]; ~0u where the rays are not
    /// coherent (nothing traced).
    template <bool Any, Isa I, class Wrap, class Hook>
    [[gnu::always_inline]] unsigned traverse_packet(IsaTag<I>, Ray<float>* r, StoreHit<float>* h, RayDataOf<P>* world,
                                                    int n, Wrap& wrap, Hook& hook, detail::PacketEntry* stack) const {
        alignas(64) detail::PacketRaySoa soa;
        soa.load(r, n, [&](int k) { return r[k].tmax; });
        const detail::PacketShape shape = detail::packet_shape(soa, n);
        if (!shape.coherent || bvh_.nodes().empty()) return ~0u;
        for (int k = 0; k < n; ++k) world[k] = leaves_.prepare(r[k]);
        const detail::PacketBoxTest<I> box(soa, shape);
        auto leaf = [&](unsigned lanes, std::uint32_t first, std::uint32_t count, float* tmax)
                        __attribute__((always_inline)) {
            unsigned hit = 0;
            for (unsigned m = lanes; m; m &= m - 1) {
                const int k = std::countr_zero(m);
                LeafQuery<P, Any> q(leaves_, r[k], world[k], h[k]);
                if (!wrap(q)(first, count)) continue;
                hit |= 1u << k;
                if constexpr (!Any) tmax[k] = r[k].tmax;
            }
            return hit;
        };
        return detail::packet_traverse<Any, N, I>(bvh_.nodes().data(), box, soa.tmax, shape.lanes, leaf, hook, stack);
    }
    /// Counts a packet's node visit and its ray-node tests into `c`.
    static auto packet_counting(WideBvhCounters& c) {
        return [&c](unsigned lanes) {
            ++c.packets;
            c.nodes += std::uint64_t(std::popcount(lanes));
        };
    }

    /// The tree over triangles tri(0 ... n - 1). Each temporary is allocated once at its
    /// size, left uninitialized where every element is written, and released before the
    /// leaves' store (sized once) is filled: no array of boxes (build_binary_bvh takes them
    /// from the triangles), no copy of the triangles in leaf order (each leaf's are gathered).
    template <class Get>
    void build(std::size_t n, Get&& tri, const BvhBuildOptions& opt) {
        if (n > std::size_t(detail::wide_max_first))
            throw Error("MeshBvh: " + std::to_string(n) + " triangles, at most 2^27 - 2");
        const auto box = [&](std::uint32_t j) {
            const TriangleVertices<float> t = tri(j);
            AABB<float> b;  // an empty box (left out) where the triangle cannot be hit
            if (detail::can_be_hit(t))
                for (const auto& p : t) b.extend(p);
            return b;
        };
        const auto clip = [&](std::uint32_t j, int axis, const AABB<float>& region) {
            const TriangleVertices<float> t = tri(j);
            return clip_triangle(t[0], t[1], t[2], axis, region);
        };
        bvh_ = WideBvh<N, B, L>(build_binary_bvh(n, box, opt, clip), opt);
        const std::vector<std::uint32_t>& prims = bvh_.prims();
        std::size_t records = 0, leaves = 0;
        for (const auto& node : bvh_.nodes())
            for (int i = 0; i < N; ++i)
                if (node.child[i] != detail::wide_empty_ref && detail::wide_is_leaf(node.child[i]))
                    records += detail::padded(detail::wide_leaf_count(node.child[i])), ++leaves;
        leaves_.reserve(records, leaves);
        // Each leaf's triangles gathered in leaf order into one small buffer.
        std::vector<TriangleVertices<float>> leaf(opt.max_leaf);
        bvh_.remap_leaves([&](std::uint32_t first, std::uint32_t count) {
            if (count > leaf.size()) leaf.resize(count);
            for (std::uint32_t k = 0; k < count; ++k) leaf[k] = tri(prims[first + k]);
            return leaves_.add(std::span(leaf).first(count), std::span(prims).subspan(first, count));
        });
    }

    WideBvh<N, B, L> bvh_;
    TriangleLeaves<P> leaves_;
};

}  // namespace glint
