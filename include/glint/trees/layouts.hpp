// glint/trees/layouts.hpp: node layouts, the policies that encode a BuiltTree into an
// array of equal-size nodes (tree.hpp's EncodedNode) and tell traversal where children are.
//
// Szécsi 2009, §4.4 (Fig. 4.3):
// - PointerLayout: every split node carries the index of its first child; the two children
//   are adjacent (right = left + 1), so one index per split node suffices.
// - HavranSubtrees<K> (Havran 2001, as Szécsi 2009 describes it): the tree is cut into compact
//   subtrees of K = 2^d - 1 slots; inside a subtree the children of local slot n are
//   2n + 1 and 2n + 2. The last level of a subtree holds pointers only: every node that
//   falls on it, split or leaf, becomes a pointer to the root of a fresh subtree. Slots below
//   a leaf inside a subtree ("orphaned trees below leaf nodes") stay unused.
// - CompactSubtrees<K> (Szécsi 2009's layout): the same compact subtrees, but
//   (a) a leaf that falls on the pointer level is stored in the pointer's slot ("the pointer
//   level of the cache line may also contain leaves"), and (b) when a branch ends early, the
//   would-be children of the leaf become roots of free subtrees whose locations are
//   recorded; a later pointer continues another branch in such a hole instead of a new
//   subtree. Repair/interpretation: the text gives no rule for choosing among holes; glint
//   takes the smallest free subtree at least as tall as the branch (capped at the tallest
//   hole), else the tallest hole, else a new subtree. Holes of height 1 sit on the pointer
//   level and cannot hold a split node, so they stay unused (and count as wasted).
// Subtrees are filled breadth-first between subtrees: pending pointers form a queue, and a
// pointer's target is chosen only when the pointer leaves the queue, so that every hole made
// up to then (by this subtree and by its siblings) is available to it.
//
// Accounting (LayoutStats): slots allocated, split/leaf/pointer nodes, wasted slots, node
// bytes and node bytes per triangle. Szécsi 2009, Fig. 4.6 compares exactly these node bytes.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

namespace detail {

inline void check_index(std::size_t i) {
    if (i > node_max_index)
        throw Error("glint trees: " + std::to_string(i) +
                    " nodes exceed the 2^29 a node index can address; split the scene");
}

}  // namespace detail

/// Every split node stores its first child's index; children are adjacent.
struct PointerLayout {
    /// Encodes `tree` into `out` (replaced), leaf i covering leaf_groups[i]; returns its
    /// accounting. Throws Error past 2^29 nodes (detail::node_max_index).
    template <class T, class Node>
    static LayoutStats encode(const BuiltTree<T>& tree, std::span<const std::array<std::uint32_t, 2>> leaf_groups,
                              std::vector<Node>& out) {
        out.assign(1, Node{});
        LayoutStats s{};
        encode_node(tree, leaf_groups, out, 0, 0, s);
        s.slots = out.size();
        s.node_size = sizeof(Node);
        s.triangles = tree.triangle_count;
        return s;
    }

    /// Index of split node n's left child (the right one follows it); read from the node.
    template <class Node>
    static std::uint32_t first_child(const Node& n, std::uint32_t, std::uint32_t) {
        return n.child();
    }
    /// Base of the block holding a node: always 0 (one block, no subtrees).
    static std::uint32_t block_base(std::uint32_t) { return 0; }

private:
    template <class T, class Node>
    static void encode_node(const BuiltTree<T>& tree, std::span<const std::array<std::uint32_t, 2>> leaf_groups,
                            std::vector<Node>& out, std::uint32_t b, std::size_t slot, LayoutStats& s) {
        const BuildNode<T>& bn = tree.nodes[b];
        if (bn.leaf) {
            out[slot] = Node::leaf(leaf_groups[b][0], leaf_groups[b][1]);
            ++s.leaf_nodes;
            return;
        }
        const std::size_t c = out.size();
        detail::check_index(c + 1);
        out.resize(c + 2);
        out[slot] = Node::split(bn, static_cast<std::uint32_t>(c));
        ++s.split_nodes;
        encode_node(tree, leaf_groups, out, bn.left, c, s);
        encode_node(tree, leaf_groups, out, bn.right, c + 1, s);
    }
};

namespace detail {

/// Compact subtrees of K = 2^d - 1 slots, with (Compact) or without (Havran) Szécsi 2009's reuse of
/// orphaned subtrees and leaves in pointer slots.
template <std::uint32_t K, bool Compact>
struct SubtreeLayout {
    static_assert(K >= 3 && ((K + 1) & K) == 0, "subtree size K must be 2^d - 1 with d >= 2");
    static constexpr std::uint32_t subtree_size = K;
    static constexpr std::uint32_t depth = std::bit_width(K);  // d levels
    static constexpr std::uint32_t half = (K - 1) / 2;         // local slots >= half: pointer level

    template <class Node>
    static std::uint32_t first_child(const Node&, std::uint32_t index, std::uint32_t base) {
        return index + (index - base) + 1;  // base + 2 (index - base) + 1
    }
    static std::uint32_t block_base(std::uint32_t index) { return index - index % K; }

    template <class T, class Node>
    static LayoutStats encode(const BuiltTree<T>& tree, std::span<const std::array<std::uint32_t, 2>> leaf_groups,
                              std::vector<Node>& out) {
        Encoder<T, Node> e{tree, leaf_groups, out};
        return e.run();
    }

private:
    static std::uint32_t level(std::uint32_t local) { return std::bit_width(local + 1) - 1; }

    template <class T, class Node>
    struct Encoder {
        const BuiltTree<T>& tree;
        std::span<const std::array<std::uint32_t, 2>> leaf_groups;
        std::vector<Node>& out;
        std::vector<std::uint32_t> heights{};
        std::vector<char> used{};
        std::array<std::vector<std::uint32_t>, 64> holes{};  // free subtree roots by height
        std::deque<std::array<std::uint32_t, 3>> pending{};  // (height, built node, pointer slot)
        LayoutStats s{};

        LayoutStats run() {
            out.clear();
            heights.assign(tree.nodes.size(), 1);
            for (std::size_t i = tree.nodes.size(); i-- > 0;) {  // children follow parents
                const auto& n = tree.nodes[i];
                if (!n.leaf) heights[i] = 1 + std::max(heights[n.left], heights[n.right]);
            }
            place(0, new_subtree());
            while (!pending.empty()) {
                const std::array<std::uint32_t, 3> item = pending.front();
                pending.pop_front();
                const std::uint32_t b = item[1], ptr = item[2];
                const std::uint32_t target = allocate(heights[b]);
                write(ptr, Node::pointer(target));
                place(b, target);
            }
            s.slots = out.size();
            std::size_t u = 0;
            for (char c : used) u += c != 0;
            s.wasted_slots = s.slots - u;
            s.node_size = sizeof(Node);
            s.triangles = tree.triangle_count;
            return s;
        }

        std::uint32_t new_subtree() {
            const std::size_t base = out.size();
            detail::check_index(base + K);
            out.resize(base + K, Node{});
            used.resize(base + K, 0);
            return static_cast<std::uint32_t>(base);
        }

        /// Root slot for a branch of height h reached through a pointer.
        std::uint32_t allocate(std::uint32_t h) {
            if constexpr (Compact) {
                const std::uint32_t want = std::min(h, depth - 1);
                for (std::uint32_t k = want; k <= depth - 1; ++k)
                    if (!holes[k].empty()) return take(k);
                for (std::uint32_t k = want; k-- > 2;)
                    if (!holes[k].empty()) return take(k);
            }
            return new_subtree();
        }
        std::uint32_t take(std::uint32_t k) {
            const std::uint32_t slot = holes[k].back();
            holes[k].pop_back();
            return slot;
        }

        void write(std::uint32_t slot, const Node& n) {
            out[slot] = n;
            used[slot] = 1;
        }

        void place(std::uint32_t b, std::uint32_t slot) {
            const BuildNode<T>& bn = tree.nodes[b];
            const std::uint32_t base = block_base(slot), local = slot - base;
            if (local >= half) {  // pointer level
                if (bn.leaf && Compact) {
                    write(slot, Node::leaf(leaf_groups[b][0], leaf_groups[b][1]));
                    ++s.leaf_nodes;
                    return;
                }
                ++s.pointer_nodes;
                used[slot] = 1;
                pending.push_back({heights[b], b, slot});
                return;
            }
            if (bn.leaf) {
                write(slot, Node::leaf(leaf_groups[b][0], leaf_groups[b][1]));
                ++s.leaf_nodes;
                if constexpr (Compact) {
                    const std::uint32_t h = depth - level(local) - 1;  // height of the holes
                    if (h >= 2) {
                        holes[h].push_back(base + 2 * local + 1);
                        holes[h].push_back(base + 2 * local + 2);
                    }
                }
                return;
            }
            write(slot, Node::split(bn, 0));
            ++s.split_nodes;
            place(bn.left, base + 2 * local + 1);
            place(bn.right, base + 2 * local + 2);
        }
    };
};

}  // namespace detail

/// Havran's compact subtrees of K nodes: pointers on the last level only.
template <std::uint32_t K>
struct HavranSubtrees : detail::SubtreeLayout<K, false> {};

/// Szécsi 2009's compact subtrees of K nodes: leaves in pointer slots, orphaned subtrees reused.
template <std::uint32_t K>
struct CompactSubtrees : detail::SubtreeLayout<K, true> {};

}  // namespace glint
