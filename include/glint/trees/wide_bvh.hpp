// glint/trees/wide_bvh.hpp: the wide (4- or 8-ary) BVH over primitive boxes and its
// traversal, for any primitives: the leaf test is the caller's callable (a LeafTest).
//
// Build: the binned SAH binary tree (bvh_builder.hpp), collapsed to N-wide nodes
// (wide_collapse.hpp), arranged in memory by a layout policy (wide_layouts.hpp), the child
// boxes stored as floats or quantized (wide_node.hpp).
//
// Traversal: children whose box the ray enters (wide_box_test.hpp) are visited nearest
// first; the others go on a stack with their entry distance and are dropped when popped
// beyond the closest hit. Any-hit queries sort nothing and test a node's leaves first.
//
// Thread safety: traversal is const and keeps its state on the caller's stack; any number
// of threads may query one tree at once.
#pragma once

#include <algorithm>
#include <bit>
#include <cassert>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/cache_line_allocator.hpp>
#include <glint/core/error.hpp>
#include <glint/core/isa.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle_leaves.hpp>
#include <glint/trees/bvh_builder.hpp>
#include <glint/trees/wide_box_test.hpp>
#include <glint/trees/wide_collapse.hpp>
#include <glint/trees/wide_layouts.hpp>
#include <glint/trees/wide_node.hpp>

namespace glint {

/// What WideBvh::intersect calls at every inner node whose children it tests (`hook()`).
template <class H>
concept NodeHook = std::invocable<H&>;

/// The default node hook: nothing.
struct NoNodeHook {
    void operator()() const noexcept {}  ///< Does nothing; traversal compiles as without a hook.
};

/// What one or more queries did (for measurements): nodes whose children were tested, and
/// leaves and records (lanes of padded batches) tested.
struct WideBvhCounters {
    /// Inner nodes whose children were tested.
    std::uint64_t nodes = 0, leaves = 0, records = 0;  ///< Records tested, padding lanes included.
    /// @var leaves
    /// Leaves whose records were tested.
    std::uint64_t packets = 0;  ///< Ray streams (MeshBvh): node visits of packets and of single rays.
};

/// N-wide BVH (N = 4 or 8) over primitive boxes, child boxes stored as B says, nodes
/// arranged in memory by layout policy L; leaves are ranges of prims(), or of whatever
/// remap_leaves() made them.
template <int N, WideBoxes B = WideBoxes::floats, WideNodeLayout L = WideBuildOrder>
class WideBvh {
    static_assert(N == 4 || N == 8, "WideBvh: 4- or 8-wide nodes");

public:
    using Node = std::conditional_t<B == WideBoxes::floats, WideBvhNode<N>, WideBvhQNode<N>>;  ///< Node type B selects.
    static constexpr int width = N;             ///< Children per node (4 or 8).
    static constexpr WideBoxes box_format = B;  ///< How child boxes are stored.
    /// Stack entries: a step pushes at most N - 1 more than it pops, so a tree of depth D
    /// needs (N - 1) D + 1; build() refuses deeper trees.
    static constexpr int max_stack = 512;

    WideBvh() = default;
    /// Over boxes[i] for every i whose box is not empty and finite; `clip` chops primitives
    /// for spatial splits (build_binary_bvh).
    template <PrimitiveClipper Clip = NoClipper>
    explicit WideBvh(std::span<const AABB<float>> boxes, const BvhBuildOptions& opt = {}, const Clip& clip = {})
        : WideBvh(build_binary_bvh(boxes, opt, clip), opt) {}
    /// Over the binary tree `binary` (build_binary_bvh with the same `opt`), whose memory
    /// it takes over (its primitive order) or releases (its nodes) before returning.
    WideBvh(BinaryBvh&& binary, const BvhBuildOptions& opt) {
        BinaryBvh bin = std::move(binary);
        prims_ = std::move(bin.prims);
        if (prims_.empty()) return;
        detail::WideNodes<N> wide = detail::WideFill<N>(bin, opt, stats_).take();
        detail::wide_arrange<L>(wide);
        detail::wide_store(std::move(wide), nodes_);
        stats_.nodes = nodes_.size();
        stats_.node_bytes = nodes_.size() * sizeof(Node);
        if ((N - 1) * stats_.depth + 1 > std::uint32_t(max_stack))
            throw Error("WideBvh: depth " + std::to_string(stats_.depth) + " needs more than " +
                        std::to_string(max_stack) + " stack entries");
    }

    /// Primitive order: leaf (first, count) covers prims()[first ... first + count - 1].
    const std::vector<std::uint32_t>& prims() const { return prims_; }
    /// Nodes in the layout's order, root at 0, cache-line aligned; empty for an empty tree.
    const std::vector<Node, detail::CacheLineAllocator<Node>>& nodes() const { return nodes_; }
    const WideBvhStats& stats() const { return stats_; }  ///< Node count and bytes, depth, leaves, SAH cost.

    /// Replaces every leaf's (first, count) by f(first, count) (a pair), e.g. to point
    /// leaves at records laid out in leaf order. Leaves are visited in node order.
    template <class F>
    void remap_leaves(F&& f) {
        for (Node& n : nodes_)
            for (int i = 0; i < N; ++i)
                if (n.child[i] != detail::wide_empty_ref && detail::wide_is_leaf(n.child[i])) {
                    const auto [first, count] = f(detail::wide_leaf_first(n.child[i]), detail::wide_leaf_count(n.child[i]));
                    n.child[i] = detail::wide_leaf(first, count);
                }
    }

    /// Closest (Any = false) or any hit: `leaf(first, count)` is called for the leaves the
    /// ray enters, nearest first; it lowers ray.tmax to each hit it finds (closest hit).
    /// `node_hook()` is called at every inner node whose children are tested (for
    /// measurements; the default does nothing). Runs the kernels of isa(), the leaf
    /// callable compiled with them.
    template <bool Any, LeafTest Leaf, NodeHook Hook = NoNodeHook>
    [[gnu::always_inline]] bool intersect(Ray<float>& ray, Leaf&& leaf, Hook&& node_hook = {}) const {
        return dispatch([&](auto kernels) __attribute__((always_inline)) { return intersect<Any>(kernels, ray, leaf, node_hook); });
    }
    /// intersect() with kernels I, inside a query that dispatch() runs (elsewhere the AVX2
    /// kernels do not compile unless the flags give AVX2).
    template <bool Any, Isa I, LeafTest Leaf, NodeHook Hook = NoNodeHook>
    [[gnu::always_inline]] bool intersect(IsaTag<I>, Ray<float>& ray, Leaf&& leaf, Hook&& node_hook = {}) const {
        if (nodes_.empty() || !detail::wide_ray_valid(ray)) return false;
        // Intervals starting below 0 take the box test that widens both ends (see
        // wide_box_test.hpp); the usual ones keep the cheaper test, with no per-node check.
        if (ray.tmin < 0.0f) [[unlikely]]
            return traverse<Any, I, true>(ray, leaf, node_hook);
        return traverse<Any, I, false>(ray, leaf, node_hook);
    }
    /// Runs `query(IsaTag<I>{})` with isa()'s kernels: those above what the flags compile
    /// (AVX2, AVX-512) in functions compiled for them whatever the flags, with what they call
    /// inlined. AVX-512 runs the AVX2 kernels (I = avx2) compiled for AVX-512. A query keeps
    /// its ray and hit in locals of its own (a dispatch around a traversal whose ray the
    /// caller holds would make the compiler keep that ray in memory).
    template <class Query>
    [[gnu::always_inline]] bool dispatch(Query&& query) const {
#if GLINT_X86
        if constexpr (compiled_isa < Isa::avx2) {  // the caller stays small: every kernel out of line
#if GLINT_AVX512_KERNELS
            if (isa_ == Isa::avx512) [[likely]] return dispatch_avx512(query);
#endif
            if (isa_ == Isa::avx2) [[likely]] return dispatch_avx2(query);
            return dispatch_other(query);
        } else
#endif
        {
            return query(IsaTag<std::min(compiled_isa, Isa::avx2)>{});  // the flags' kernels: the only ones compiled
        }
    }

    /// The kernels queries run (core/isa.hpp): best_isa() from construction on.
    Isa isa() const { return isa_; }
    /// Runs queries with `isa`'s kernels (every choice gives the same hits); throws
    /// glint::Error where this build and CPU cannot run them.
    void set_isa(Isa isa) {
        if (!isa_supported(isa)) throw Error(std::string("WideBvh::set_isa: this CPU cannot run ") + isa_name(isa));
        isa_ = isa;
    }

private:
    template <class Query>
    [[gnu::noinline, gnu::flatten]] GLINT_TARGET_AVX2 bool dispatch_avx2(Query& query) const {
        return query(IsaTag<Isa::avx2>{});
    }
#if GLINT_AVX512_KERNELS
    /// The AVX2 kernels compiled for AVX-512 (core/isa.hpp: GLINT_TARGET_AVX512).
    template <class Query>
    [[gnu::noinline, gnu::flatten]] GLINT_TARGET_AVX512 bool dispatch_avx512(Query& query) const {
        return query(IsaTag<Isa::avx2>{});
    }
#endif
    /// The kernels other than AVX2 where the flags do not give AVX2 (SSE2, and the portable
    /// loops for tests and comparisons).
    template <class Query>
    [[gnu::noinline, gnu::flatten]] bool dispatch_other(Query& query) const {
#if GLINT_X86
        if (isa_ == Isa::sse2) return query(IsaTag<Isa::sse2>{});
#endif
        return query(IsaTag<Isa::portable>{});
    }

    /// intersect() for a valid ray, with the box test for intervals starting below 0 or not.
    template <bool Any, Isa I, bool Signed, class Leaf, class Hook>
    [[gnu::always_inline]] bool traverse(Ray<float>& ray, Leaf& leaf, Hook& node_hook) const {
        if constexpr (Any)
            return traverse_any<I, Signed>(ray, leaf, node_hook);
        else
            return traverse_closest<I, Signed>(ray, leaf, node_hook);
    }

    /// Closest hit: children nearest first; a leaf's hit lowers ray.tmax, which culls the
    /// stacked children beyond it.
    template <Isa I, bool Signed, class Leaf, class Hook>
    [[gnu::always_inline]] bool traverse_closest(Ray<float>& ray, Leaf& leaf, Hook& node_hook) const {
        const detail::WideBoxTest<N, I, Signed> box(ray);
        struct Entry {
            std::uint32_t ref;
            float t;
        };
        Entry stack[max_stack];
        int sp = 0;
        bool found = false;
        std::uint32_t ref = 0;
        for (;;) {
            if (!detail::wide_is_leaf(ref)) {
                alignas(32) float tn[N];
                const Node& n = nodes_[ref];
                node_hook();
                unsigned mask = box.test(n, ray.tmin, ray.tmax, tn);
                if (mask != 0) {
                    // The nearest child is visited next without a trip through the stack (as
                    // Embree's BVH-N traversal does); on equal distances the later child first.
                    const int i0 = std::countr_zero(mask);
                    mask &= mask - 1;
                    if (mask == 0) {  // one child
                        ref = n.child[i0];
                        continue;
                    }
                    const int i1 = std::countr_zero(mask);
                    mask &= mask - 1;
                    const bool later = !(tn[i0] < tn[i1]);
                    Entry near{n.child[later ? i1 : i0], tn[later ? i1 : i0]};
                    stack[sp++] = Entry{n.child[later ? i0 : i1], tn[later ? i0 : i1]};
                    prefetch(stack[sp - 1].ref);
                    if (mask == 0) {  // two children: the nearer is read next, without a prefetch
                        ref = near.ref;
                        continue;
                    }
                    const int first = sp - 1;
                    stack[sp++] = near;
                    prefetch(near.ref);
                    for (; mask; mask &= mask - 1) {  // insertion by distance, nearest on top
                        const int i = std::countr_zero(mask);
                        int j = sp++;
                        for (; j > first && stack[j - 1].t < tn[i]; --j) stack[j] = stack[j - 1];
                        stack[j] = Entry{n.child[i], tn[i]};
                        prefetch(n.child[i]);
                    }
                    assert(sp <= max_stack);
                    ref = stack[--sp].ref;  // the nearest: within the interval, no test
                    continue;
                }
            } else if (leaf(detail::wide_leaf_first(ref), detail::wide_leaf_count(ref))) {
                found = true;
            }
            do {
                if (sp == 0) return found;
                --sp;
            } while (!(stack[sp].t <= detail::wide_exit_bound<Signed>(ray.tmax)));
            ref = stack[sp].ref;
        }
    }

    /// Any hit: no child is sorted by distance (the interval never shrinks, so the order only
    /// decides which hit ends the query, and sorting costs every node). At a node, the leaves
    /// entered are tested at once, in the order they are stored, before any inner child is
    /// visited: each is a chance to end the query that costs no further node visit. The
    /// inner children go on the stack; the last pushed is visited next.
    template <Isa I, bool Signed, class Leaf, class Hook>
    [[gnu::always_inline]] bool traverse_any(const Ray<float>& ray, Leaf& leaf, Hook& node_hook) const {
        const detail::WideBoxTest<N, I, Signed> box(ray);
        std::uint32_t stack[max_stack];
        int sp = 0;
        std::uint32_t ref = 0;  // the root: an inner node (a tree of one leaf has a root node too)
        for (;;) {
            alignas(32) float tn[N];
            const Node& n = nodes_[ref];
            node_hook();
            for (unsigned mask = box.test(n, ray.tmin, ray.tmax, tn); mask; mask &= mask - 1) {
                const std::uint32_t c = n.child[std::countr_zero(mask)];
                if (!detail::wide_is_leaf(c)) {
                    stack[sp++] = c;
                    prefetch(c);
                } else if (leaf(detail::wide_leaf_first(c), detail::wide_leaf_count(c))) {
                    return true;
                }
            }
            assert(sp <= max_stack);
            if (sp == 0) return false;
            ref = stack[--sp];
        }
    }

    /// Asks for the cache lines of inner node `ref` (a child about to be visited or pushed).
    [[gnu::always_inline]] void prefetch(std::uint32_t ref) const {
        if (!detail::wide_is_leaf(ref)) {
            const char* p = reinterpret_cast<const char*>(&nodes_[ref]);
            for (std::size_t line = 0; line < sizeof(Node); line += 64) __builtin_prefetch(p + line, 0, 3);
        }
    }

    std::vector<Node, detail::CacheLineAllocator<Node>> nodes_;
    std::vector<std::uint32_t> prims_;
    WideBvhStats stats_;
    Isa isa_ = best_isa();
};

}  // namespace glint
