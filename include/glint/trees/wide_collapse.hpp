// glint/trees/wide_collapse.hpp: the binned SAH binary tree (bvh_builder.hpp) becomes an
// N-wide one by the collapse of least SAH cost (Ylitie, Karras, Laine 2017, §3.1), chosen by
// dynamic programming over the binary nodes: which binary subtrees become a wide node's
// children, and which become one leaf. (Wald, Benthin, Boulos, "Getting rid of packets",
// 2008, Dammertz, Hanika, Keller, "Shallow bounding volume hierarchies", 2008, and Ernst and
// Greiner, "Multi bounding volume hierarchies", 2008, introduced N-ary BVHs for single rays.)
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/math.hpp>
#include <glint/trees/bvh_builder.hpp>
#include <glint/trees/wide_node.hpp>

namespace glint {

namespace detail {

/// The collapse of a binary SAH tree into an N-wide one that minimizes the wide tree's SAH
/// cost (Ylitie, Karras, Laine 2017, §3.1), by dynamic programming over the binary
/// nodes. A binary subtree s fills one or more child slots of a wide node; as one slot it
/// is a wide leaf (the whole subtree's primitives, at most max_leaf of them, costing C_I per
/// started block of leaf_block) or a wide node (C_N, BvhBuildOptions::wide_node_cost, then
/// its children, in 2 ... N slots); every cost is weighted by the surface area of its box,
/// the SAH's estimate of the rays that enter it. cost(s, i), s in at most i slots, is the
/// cheapest of s in i - 1 slots and of i slots shared between s's two children; equal
/// costs go to fewer wide nodes. The solution is read back top-down. Unlike opening
/// children greedily by area, this fills nodes whose children would otherwise be few, and
/// merges small sibling leaves into one.
template <int N>
class WideCollapse {
public:
    /// Solves the collapse of binary tree `bin`, whose root is an inner node.
    WideCollapse(const BinaryBvh& bin, const BvhBuildOptions& opt) : bin_(bin), at_(bin.nodes.size()) { solve(0, opt); }
    /// Binary subtree s, placed in one slot: a wide leaf (or else a wide node).
    bool is_leaf(std::uint32_t s) const { return at_[s].leaf; }
    /// The children of the wide node made of binary inner node s; returns how many (2 ... N).
    int children(std::uint32_t s, std::uint32_t* kids) const {
        int k = 0;
        place(s + 1, at_[s].node_left, kids, k);
        place(bin_.nodes[s].right, at_[s].node_slots - at_[s].node_left, kids, k);
        return k;
    }
    /// The SAH cost of the whole wide tree (binary node 0 as the root's wide node) per ray
    /// entering the root's box.
    double root_cost() const { return root_cost_; }

private:
    struct Slot {                 // the decisions for binary subtree s (its costs live on the stack)
        std::uint8_t left[N];     // s in at most i slots (index i - 1): 0 = as in i - 1, else the left child's slots
        bool leaf = true;         // s in one slot: a wide leaf, else a wide node
        std::uint8_t node_left = 0, node_slots = 0;  // s as a wide node: its children's slots
    };
    /// A subtree's cost, and its wide nodes to break ties: where boxes have no area (points,
    /// segments) every cost is 0, and the fewest nodes keep the tree full and shallow.
    struct Cost {
        double sah = 0;
        std::uint32_t nodes = 0;
        Cost operator+(const Cost& o) const { return {sah + o.sah, nodes + o.nodes}; }
        bool operator<(const Cost& o) const { return sah < o.sah || (sah == o.sah && nodes < o.nodes); }
    };
    using Costs = std::array<Cost, N>;  // s in at most 1 ... N slots

    /// The costs of subtree s, after its children's (post-order; recursion as deep as the tree).
    Costs solve(std::uint32_t s, const BvhBuildOptions& opt) {
        const BinaryBvhNode& b = bin_.nodes[s];
        Slot& o = at_[s];
        // In double: finite for every finite float box (a float area overflows from
        // coordinates of about 10^19).
        const double area = AABB<double>{Vec3<double>(b.box.lo), Vec3<double>(b.box.hi)}.surface_area();
        const Cost leaf{b.leaf() || b.count <= opt.max_leaf ? opt.intersection_cost * double(opt.blocks(b.count)) * area
                                                            : infinity<double>,
                        0};
        Costs cost;
        cost.fill(leaf);
        std::fill(o.left, o.left + N, std::uint8_t(0));
        if (b.leaf()) return cost;
        const Costs l = solve(s + 1, opt), r = solve(b.right, opt);
        Cost shared[N + 1];  // the cheapest sharing of exactly i slots between the children
        std::uint8_t shared_left[N + 1];
        Cost node{infinity<double>, 0};
        for (int i = 2; i <= N; ++i) {
            shared[i] = l[0] + r[i - 2], shared_left[i] = 1;
            for (int k = 2; k < i; ++k)
                if (const Cost c = l[k - 1] + r[i - k - 1]; c < shared[i]) shared[i] = c, shared_left[i] = std::uint8_t(k);
            if (shared[i] < node) node = shared[i], o.node_slots = std::uint8_t(i), o.node_left = shared_left[i];
        }
        node = node + Cost{opt.wide_node_cost * area, 1};
        if (s == 0) root_cost_ = area > 0 ? node.sah / area : 0;  // a root box of no area: no rays
        o.leaf = !(node < leaf);
        cost[0] = o.leaf ? leaf : node;
        for (int i = 2; i <= N; ++i) {
            cost[i - 1] = cost[i - 2];
            if (shared[i] < cost[i - 1]) cost[i - 1] = shared[i], o.left[i - 1] = shared_left[i];
        }
        return cost;
    }
    /// Appends the slots binary subtree s takes when it may take i of them.
    void place(std::uint32_t s, int i, std::uint32_t* kids, int& k) const {
        while (i > 1 && at_[s].left[i - 1] == 0) --i;
        if (i == 1) {
            kids[k++] = s;
            return;
        }
        const int left = at_[s].left[i - 1];
        place(s + 1, left, kids, k);
        place(bin_.nodes[s].right, i - left, kids, k);
    }

    const BinaryBvh& bin_;  // outlives the collapse: both live in WideBvh's constructor
    std::vector<Slot> at_;
    double root_cost_ = 0;
};

/// The wide nodes of binary tree `bin` (not empty) as its collapse chooses them, root first,
/// a node's children in slots 0 ... k - 1, in the order opt.node_order asks; sets `stats`'
/// depth, leaves and sah_cost.
template <int N>
class WideFill {
public:
    WideFill(const BinaryBvh& bin, const BvhBuildOptions& opt, WideBvhStats& stats) : bin_(bin), order_(opt.node_order), stats_(stats) {
        nodes_.emplace_back(empty_node());
        stats_.depth = 1;
        if (bin.nodes[0].leaf()) {  // a one-leaf tree: a root with one child
            set_child(nodes_[0], 0, bin.nodes[0], wide_leaf(bin.nodes[0].begin, bin.nodes[0].count));
            stats_.leaves = 1;
            return;
        }
        const WideCollapse<N> collapse(bin, opt);
        stats_.sah_cost = float(collapse.root_cost());
        fill(collapse, 0, 0, 1);
    }
    WideNodes<N> take() { return std::move(nodes_); }

private:
    static WideBvhNode<N> empty_node() {
        WideBvhNode<N> n;
        for (int i = 0; i < N; ++i) {
            for (int a = 0; a < 3; ++a) {
                n.bounds[2 * a][i] = infinity<float>;
                n.bounds[2 * a + 1][i] = -infinity<float>;
            }
            n.child[i] = wide_empty_ref;
        }
        return n;
    }
    static void set_child(WideBvhNode<N>& node, int i, const BinaryBvhNode& b, std::uint32_t ref) {
        for (int a = 0; a < 3; ++a) {
            node.bounds[2 * a][i] = b.box.lo[a];
            node.bounds[2 * a + 1][i] = b.box.hi[a];
        }
        node.child[i] = ref;
    }

    /// Fills wide node `node` from binary inner node `slot` (depth: of this wide node) with
    /// the children the collapse chose.
    void fill(const WideCollapse<N>& collapse, std::uint32_t slot, std::uint32_t node, std::uint32_t depth) {
        std::uint32_t kids[N];
        const int k = collapse.children(slot, kids);
        stats_.depth = std::max(stats_.depth, depth + 1);  // its leaves, at least
        std::uint32_t first_child = 0;
        for (int i = 0; i < k; ++i) {
            const BinaryBvhNode& c = bin_.nodes[kids[i]];
            if (collapse.is_leaf(kids[i])) {
                set_child(nodes_[node], i, c, wide_leaf(c.begin, c.count));
                ++stats_.leaves;
                continue;
            }
            const std::uint32_t child = std::uint32_t(nodes_.size());
            if (first_child == 0) first_child = child;
            nodes_.emplace_back(empty_node());
            set_child(nodes_[node], i, c, child);
            if (order_ == WideNodeOrder::depth_first) fill(collapse, kids[i], child, depth + 1);
        }
        if (order_ == WideNodeOrder::sibling_blocks)  // the inner children were placed side by side
            for (int i = 0; i < k; ++i)
                if (!collapse.is_leaf(kids[i])) fill(collapse, kids[i], first_child++, depth + 1);
    }

    const BinaryBvh& bin_;
    WideNodeOrder order_;
    WideBvhStats& stats_;
    WideNodes<N> nodes_;
};

}  // namespace detail

}  // namespace glint
