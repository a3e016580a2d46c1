// glint/trees/wide_traverse.hpp: the wide BVH's traversal loop, compiled once per instruction
// set it runs with (core/isa.hpp), and the choice among them.
//
// The loop (wide_traverse_body.inc) is included here once for the flags' own kernels, where it
// is inlined into the query, and, where the flags do not give them, once inside a region
// compiled for AVX2 and once for AVX-512 (GCC: without contracting into FMAs, so that every
// kernel gives the same floats). Inside a region the box test is inlined because it is
// `always_inline`, not because the compiler's inlining budget for the unit allows it: with the
// test carrying a `target` attribute of its own and the loop compiled for the default target,
// only `flatten` could inline it, and in units that instantiate many trees GCC's budget left it
// an out-of-line call per node (docs/trees.md, "Kernels chosen at run time").
#pragma once

#include <bit>
#include <cassert>
#include <cstdint>

#include <glint/core/isa.hpp>
#include <glint/core/ray.hpp>
#include <glint/trees/wide_box_test.hpp>
#include <glint/trees/wide_node.hpp>

namespace glint::detail {

/// Stack entries of one traversal (a tree deeper than (max - 1) / (N - 1) is refused at build).
inline constexpr int wide_max_stack = 512;

/// Asks for the cache lines of inner node `ref` of `nodes` (a child about to be visited or pushed).
template <class Node>
[[gnu::always_inline]] inline void wide_prefetch(const Node* nodes, std::uint32_t ref) {
    if (!wide_is_leaf(ref)) {
        const char* p = reinterpret_cast<const char*>(&nodes[ref]);
        for (std::size_t line = 0; line < sizeof(Node); line += 64) __builtin_prefetch(p + line, 0, 3);
    }
}

/// The loop with the flags' kernels, inlined into its query.
namespace flags {
#define GLINT_WIDE_TRAVERSE_ATTRS [[gnu::always_inline]] inline
#include <glint/trees/wide_traverse_body.inc>
#undef GLINT_WIDE_TRAVERSE_ATTRS
}  // namespace flags

// The loop compiled for AVX2 and AVX-512 where the flags do not give them: one call per query.
#define GLINT_WIDE_TRAVERSE_ATTRS [[gnu::noinline, gnu::flatten]] inline
#if GLINT_X86 && !defined(__AVX2__)
#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,bmi,bmi2,popcnt"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,bmi,bmi2,popcnt")
#endif
/// The loop compiled for AVX2.
namespace avx2 {
#include <glint/trees/wide_traverse_body.inc>
}  // namespace avx2
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif
#endif
#if GLINT_AVX512_KERNELS && !defined(__AVX512VL__)
#pragma GCC push_options
#pragma GCC target("avx2,bmi,bmi2,popcnt,avx512f,avx512vl,avx512bw,avx512dq")
#pragma GCC optimize("fp-contract=off")
/// The loop compiled for AVX-512 (with the AVX2 kernels).
namespace avx512 {
#include <glint/trees/wide_traverse_body.inc>
}  // namespace avx512
#pragma GCC pop_options
#endif
#undef GLINT_WIDE_TRAVERSE_ATTRS

/// The traversal with kernels I: the flags' loop where they give I, else I's own region's.
template <bool Any, Isa I, bool Signed, int N, class Node, class Leaf, class Hook>
[[gnu::always_inline]] inline bool wide_traverse_with(const Node* nodes, Ray<float>& ray, Leaf& leaf, Hook& node_hook) {
    constexpr Isa K = kernels_of(I);
#if GLINT_AVX512_KERNELS && !defined(__AVX512VL__)
    if constexpr (I == Isa::avx512) return avx512::wide_traverse<Any, K, Signed, N>(nodes, ray, leaf, node_hook);
    else
#endif
#if GLINT_X86 && !defined(__AVX2__)
        if constexpr (K == Isa::avx2) return avx2::wide_traverse<Any, K, Signed, N>(nodes, ray, leaf, node_hook);
    else
#endif
        return flags::wide_traverse<Any, K, Signed, N>(nodes, ray, leaf, node_hook);
}

}  // namespace glint::detail
