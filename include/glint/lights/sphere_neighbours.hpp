// glint/lights/sphere_neighbours.hpp: nearest neighbours among a changing set of spheres under
// Fernandez 2004, §5.1.2's cluster distance, the largest distance between two points of the
// spheres: d(a, b) = |c_a - c_b| + r_a + r_b. The agglomerative build of lights/cluster_tree.hpp
// asks it for the nearest live cluster of each node on its chain (Walter et al. 2008's
// nearest-neighbour queries in a kd-tree), removes the two clusters it merges and inserts
// their union.
//
// A kd-tree over the initial centres (median splits, leaves of up to 8); an insertion goes to
// the leaf its centre falls in; after an insertion or a removal the leaf's box of centres and
// smallest radius are recomputed and its ancestors' refitted (O(depth)). A subtree is skipped
// when it holds no live sphere or when distance(query centre, box) + r_query + its smallest
// radius exceeds the best distance found.
// Ties are broken by the smaller id, so the answer depends on nothing but the set.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/math.hpp>

namespace glint {

/// A sphere bounding a cluster of lights (a point light: radius 0).
template <Scalar T>
struct BoundingSphere {
    Vec3<T> centre{0};  ///< World-space centre.
    T radius = T(0);    ///< Radius, world units; >= 0.
};

/// The largest distance between a point of a and a point of b.
template <Scalar T>
T cluster_distance(const BoundingSphere<T>& a, const BoundingSphere<T>& b) {
    return glm::length(a.centre - b.centre) + a.radius + b.radius;
}

/// The smallest sphere that holds spheres a and b.
template <Scalar T>
BoundingSphere<T> enclosing_sphere(const BoundingSphere<T>& a, const BoundingSphere<T>& b) {
    const T d = glm::length(b.centre - a.centre);
    if (d + b.radius <= a.radius) return a;
    if (d + a.radius <= b.radius) return b;
    const T r = (d + a.radius + b.radius) * T(0.5);
    return {a.centre + (b.centre - a.centre) * ((r - a.radius) / d), r};
}

/// Nearest-neighbour queries under the cluster distance among a set of spheres that changes by
/// removal and insertion: a refitted kd-tree. Not thread-safe while it changes.
template <Scalar T>
class SphereNeighbours {
public:
    static constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();  ///< No sphere.
    /// A query's answer.
    struct Nearest {
        T distance = infinity<T>;  ///< Cluster distance to it (infinity: no other live sphere).
        std::uint32_t id = none;   ///< The nearest sphere's id (none: no other live sphere).
    };

    /// A tree over the spheres `ids` (all live, distinct) of `spheres`, the caller's array,
    /// indexed by id, which may grow (inserted ids) but must hold every live sphere.
    SphereNeighbours(const std::vector<BoundingSphere<T>>& spheres, std::vector<std::uint32_t> ids) : spheres_(&spheres) {
        where_.assign(ids.empty() ? 0 : std::size_t(*std::max_element(ids.begin(), ids.end())) + 1, none);
        if (!ids.empty()) build(ids, 0, std::uint32_t(ids.size()), none);
    }

    /// Removes live sphere `id` from the set (precondition: it is live); O(depth).
    void remove(std::uint32_t id) {
        Node& leaf = nodes_[where_[id]];
        leaf.items.erase(std::find_if(leaf.items.begin(), leaf.items.end(), [&](const Item& it) { return it.id == id; }));
        refit(where_[id]);
    }

    /// Adds sphere `id`, already in the caller's array, to the leaf its centre falls in; O(depth).
    void insert(std::uint32_t id) {
        const Vec3<T>& c = (*spheres_)[id].centre;
        std::uint32_t k = 0;
        while (nodes_[k].left != none) k = c[nodes_[k].axis] < nodes_[k].split ? nodes_[k].left : nodes_[k].left + 1;
        nodes_[k].items.push_back({(*spheres_)[id], id});
        if (where_.size() <= id) where_.resize(std::size_t(id) + 1, none);
        where_[id] = k;
        refit(k);
    }

    /// The live sphere nearest to sphere `id` (not itself), smallest id among equals. A live
    /// sphere's search starts in its own leaf and climbs, searching each sibling subtree on the
    /// way up: the nearby spheres come first and the rest of the tree is mostly pruned.
    Nearest nearest(std::uint32_t id) const {
        const BoundingSphere<T>& q = (*spheres_)[id];
        Nearest best;
        std::uint32_t k = id < where_.size() ? where_[id] : none;
        if (k == none) {  // not in the tree: search it all
            search(0, q, id, best);
            return best;
        }
        search(k, q, id, best);
        for (std::uint32_t p = nodes_[k].parent; p != none; k = p, p = nodes_[p].parent)
            search(nodes_[p].left == k ? k + 1 : nodes_[p].left, q, id, best);
        return best;
    }

    /// The structure's memory: nodes, their items and the id-to-leaf map.
    std::size_t bytes() const {
        std::size_t b = nodes_.capacity() * sizeof(Node) + where_.capacity() * sizeof(std::uint32_t);
        for (const Node& n : nodes_) b += n.items.capacity() * sizeof(Item);
        return b;
    }

private:
    struct Item {  // a sphere and its id, kept in its leaf (no lookup while searching)
        BoundingSphere<T> sphere;
        std::uint32_t id;
    };
    struct Node {
        AABB<T> box;
        std::uint32_t left = none;  // children left, left + 1; none for a leaf
        std::uint32_t parent = none;
        bool live = false;    // any live sphere below
        T min_radius = T(0);  // of the live spheres below
        int axis = 0;
        T split = T(0);
        std::vector<Item> items;
    };

    /// Leaf k's box, liveness and smallest radius from its spheres, then its ancestors' from
    /// their children, up to the first ancestor they leave unchanged (its own ancestors then
    /// are too): the bounds stay tight as spheres come and go.
    void refit(std::uint32_t k) {
        Node& leaf = nodes_[k];
        leaf.box = AABB<T>{};
        leaf.min_radius = infinity<T>;
        leaf.live = !leaf.items.empty();
        for (const Item& it : leaf.items) {
            leaf.box.extend(it.sphere.centre);
            leaf.min_radius = std::min(leaf.min_radius, it.sphere.radius);
        }
        for (k = leaf.parent; k != none; k = nodes_[k].parent) {
            Node& n = nodes_[k];
            const Node &a = nodes_[n.left], &b = nodes_[n.left + 1];
            AABB<T> box = a.box;
            box.extend(b.box);
            const T min_radius = std::min(a.min_radius, b.min_radius);
            const bool live = a.live || b.live;
            if (live == n.live && min_radius == n.min_radius && box.lo == n.box.lo && box.hi == n.box.hi) break;
            n.box = box;
            n.min_radius = min_radius;
            n.live = live;
        }
    }

    /// Searches the subtree at `root` for spheres nearer to q than `best`, depth first, the
    /// child on q's side of the split first; subtrees that cannot hold one are pruned.
    void search(std::uint32_t root, const BoundingSphere<T>& q, std::uint32_t id, Nearest& best) const {
        std::uint32_t stack[128];
        int top = 0;
        stack[top++] = root;
        while (top > 0) {
            const Node& node = nodes_[stack[--top]];
            if (!node.live || box_distance(node.box, q.centre) + q.radius + node.min_radius > best.distance) continue;
            if (node.left == none) {
                for (const Item& it : node.items) consider(q, id, it, best);
                continue;
            }
            const bool near_left = q.centre[node.axis] < node.split;
            stack[top++] = near_left ? node.left + 1 : node.left;  // the far child is searched last
            stack[top++] = near_left ? node.left : node.left + 1;
        }
    }

    static T box_distance(const AABB<T>& b, const Vec3<T>& p) {
        const Vec3<T> d = glm::max(glm::max(b.lo - p, p - b.hi), Vec3<T>(0));
        return glm::length(d);
    }

    static void consider(const BoundingSphere<T>& q, std::uint32_t id, const Item& it, Nearest& best) {
        if (it.id == id) return;
        const T d = cluster_distance(q, it.sphere);
        if (d < best.distance || (d == best.distance && it.id < best.id)) best = {d, it.id};
    }

    /// Builds the tree over ids[lo, hi) from node 0, depth first with an explicit stack.
    void build(std::vector<std::uint32_t>& ids, std::uint32_t lo, std::uint32_t hi, std::uint32_t parent) {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> todo{{lo, hi}};
        std::vector<std::uint32_t> parents{parent};
        nodes_.emplace_back();
        std::vector<std::uint32_t> slots{0};
        while (!todo.empty()) {
            const auto [a, b] = todo.back();
            const std::uint32_t k = slots.back(), p = parents.back();
            todo.pop_back(), slots.pop_back(), parents.pop_back();
            Node& node = nodes_[k];
            node.parent = p;
            node.live = b > a;
            for (std::uint32_t i = a; i < b; ++i) node.box.extend((*spheres_)[ids[i]].centre);
            if (b - a <= 8) {
                for (std::uint32_t i = a; i < b; ++i) {
                    node.items.push_back({(*spheres_)[ids[i]], ids[i]});
                    where_[ids[i]] = k;
                }
                continue;
            }
            split_node(ids, a, b, k, todo, slots, parents);
        }
    }

    void split_node(std::vector<std::uint32_t>& ids, std::uint32_t a, std::uint32_t b, std::uint32_t k,
                    std::vector<std::pair<std::uint32_t, std::uint32_t>>& todo, std::vector<std::uint32_t>& slots,
                    std::vector<std::uint32_t>& parents) {
        const int axis = nodes_[k].box.longest_axis();
        const std::uint32_t mid = a + (b - a) / 2;
        const auto& s = *spheres_;
        std::nth_element(ids.begin() + a, ids.begin() + mid, ids.begin() + b, [&](std::uint32_t i, std::uint32_t j) {
            const T ci = s[i].centre[axis], cj = s[j].centre[axis];
            return ci < cj || (ci == cj && i < j);
        });
        const std::uint32_t left = std::uint32_t(nodes_.size());
        nodes_[k].axis = axis;
        nodes_[k].split = s[ids[mid]].centre[axis];
        nodes_[k].left = left;
        nodes_.emplace_back();
        nodes_.emplace_back();
        todo.push_back({a, mid}), slots.push_back(left), parents.push_back(k);
        todo.push_back({mid, b}), slots.push_back(left + 1), parents.push_back(k);
    }

    const std::vector<BoundingSphere<T>>* spheres_;
    std::vector<Node> nodes_;
    std::vector<std::uint32_t> where_;  // per id: its leaf
};

}  // namespace glint
