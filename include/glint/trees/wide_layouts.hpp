// glint/trees/wide_layouts.hpp: where the nodes of a wide BVH go in its node array. A layout
// policy returns a permutation of the collapse's node order; WideBvh always applies it (the
// default, WideBuildOrder, returns the identity).
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/trees/wide_node.hpp>

namespace glint {

/// A wide node layout policy: where the nodes of a collapsed wide BVH go in its node array.
/// `arrange<N>(nodes)` gets the nodes in the collapse's order (root first; a child word
/// without the leaf bit is an inner child's index) and returns every node's new index (a
/// permutation keeping the root at 0); WideBvh applies it (detail::wide_arrange).
template <class L>
concept WideNodeLayout = requires(std::span<const WideBvhNode<8>> n8, std::span<const WideBvhNode<4>> n4) {
    { L::template arrange<8>(n8) } -> std::same_as<std::vector<std::uint32_t>>;
    { L::template arrange<4>(n4) } -> std::same_as<std::vector<std::uint32_t>>;
};

/// The collapse's own order (BvhBuildOptions::node_order: depth first or sibling blocks):
/// every node stays where it is.
struct WideBuildOrder {
    /// The identity permutation over `nodes` (O(n)).
    template <int N>
    static std::vector<std::uint32_t> arrange(std::span<const WideBvhNode<N>> nodes) {
        std::vector<std::uint32_t> at(nodes.size());
        for (std::size_t i = 0; i < at.size(); ++i) at[i] = std::uint32_t(i);
        return at;
    }
};

/// Szécsi 2009's compact subtrees (Szécsi 2009, §4.4; layouts.hpp's CompactSubtrees) on wide
/// nodes: the nodes are stored in units of at most K consecutive nodes, each holding
/// whole subtrees (K = 18 eight-wide nodes of 224 bytes fill 4 KiB, a page; K = 9 is a node
/// and its eight children). A subtree starts with the root or with a sibling block (the
/// inner children of one node, side by side) and grows breadth first: each node met adds
/// its inner children as one block while the unit has room; a block that does not fit
/// waits in a queue (breadth first between subtrees, as in layouts.hpp, where the pointer
/// level of a subtree leads to fresh ones; here the parent's child words are the
/// pointers). A waiting block starts a fresh unit, or, while the current unit has room for
/// it, continues there: Szécsi 2009's reuse of the room a branch that ended early left.
/// Child words stay explicit indices: a wide node keeps one word per child for its leaves'
/// references anyway, so Szécsi 2009's implicit addressing inside a subtree would save only the
/// words of inner children (4 of 224 bytes per node, 8 wide) at the price of a second node
/// format; node bytes equal the collapse's order (nothing is padded).
template <std::uint32_t K>
struct WideCompactSubtrees {
    /// New index of every node (root stays at 0), units of at most K nodes as above; O(n).
    template <int N>
    static std::vector<std::uint32_t> arrange(std::span<const WideBvhNode<N>> nodes) {
        static_assert(K >= std::uint32_t(N), "WideCompactSubtrees: a unit holds at least one sibling block");
        std::vector<std::uint32_t> at(nodes.size(), 0), subtree{0}, block;
        std::deque<std::uint32_t> waiting;  // nodes whose inner children did not fit their unit
        std::uint32_t next = 1, unit = 1;   // the root stays at 0; nodes in the current unit
        auto place_children = [&](std::uint32_t p) {
            block.clear();
            for (std::uint32_t c : nodes[p].child)
                if (!detail::wide_is_leaf(c)) block.push_back(c);
            for (std::uint32_t c : block) at[c] = next++;
            unit += std::uint32_t(block.size());
        };
        auto inner_count = [&](std::uint32_t p) {
            std::uint32_t k = 0;
            for (std::uint32_t c : nodes[p].child) k += !detail::wide_is_leaf(c);
            return k;
        };
        for (;;) {
            for (std::size_t q = 0; q < subtree.size(); ++q) {  // grows while it is read
                const std::uint32_t k = inner_count(subtree[q]);
                if (k == 0) continue;
                if (unit + k > K) {
                    waiting.push_back(subtree[q]);
                    continue;
                }
                place_children(subtree[q]);
                subtree.insert(subtree.end(), block.begin(), block.end());
            }
            if (waiting.empty()) return at;
            if (unit + inner_count(waiting.front()) > K) unit = 0;  // a fresh unit
            place_children(waiting.front());
            waiting.pop_front();
            subtree = block;
        }
    }
};

namespace detail {

/// Moves the nodes where L puts them, checking that L gave a permutation keeping the root.
template <WideNodeLayout L, int N>
void wide_arrange(WideNodes<N>& wide) {
    const std::vector<std::uint32_t> at = L::template arrange<N>(std::span<const WideBvhNode<N>>(wide.data(), wide.size()));
    if (at.size() != wide.size())
        throw Error("WideBvh: the node layout placed " + std::to_string(at.size()) + " of " +
                    std::to_string(wide.size()) + " nodes");
    std::vector<char> taken(wide.size(), 0);
    for (std::size_t i = 0; i < at.size(); ++i)
        if (at[i] >= wide.size() || taken[at[i]]++ || (i == 0 && at[0] != 0))
            throw Error("WideBvh: the node layout moves node " + std::to_string(i) + " to " + std::to_string(at[i]) +
                        ", not a permutation of " + std::to_string(wide.size()) + " nodes keeping the root at 0");
    WideNodes<N> moved(wide.size());
    for (std::size_t i = 0; i < wide.size(); ++i) {
        WideBvhNode<N> n = wide[i];
        for (std::uint32_t& c : n.child)
            if (!wide_is_leaf(c)) c = at[c];
        moved[at[i]] = n;
    }
    wide = std::move(moved);
}

}  // namespace detail

}  // namespace glint
