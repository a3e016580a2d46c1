// glint/lights/cluster_tree.hpp: the light cluster tree of Fernandez 2004, §5.1.2 over point
// lights (lights/light.hpp; area lights and VPLs become points in lights/light_points.hpp).
//
// Built bottom up: every light is a leaf; the two parentless nodes closest to each other are
// merged into a new node until one is left, the root. The distance between two nodes is the
// largest distance between points of their bounding spheres (|c_a - c_b| + r_a + r_b; for two
// leaves the distance of the lights), and a node's sphere is the smallest one holding its
// children's. Each node keeps its lights' total intensity, the box of their positions, the
// cone of their axes (Conty Estevez and Kulla 2018's (axis, theta_o, theta_e): every axis
// within theta_o of `axis`, no light emitting beyond theta_e from its own axis; isotropic
// lights make theta_o = pi) and a representative light: the representative of the child
// closer to the parent's power-weighted centroid (§5.1.2), so that a parent's shadow ray is
// reused by one child when a cut is refined (lights/cuts.hpp). It also keeps that centroid and
// the power-weighted mean of the lights' axes, where a cut evaluates the node's f G.
//
// The greedy merge order's merges are found by a chain of nearest neighbours, as Walter et al.
// 2008's locally-ordered clustering: from a live node, its nearest neighbour
// (lights/sphere_neighbours.hpp), that one's, and so on, until two are each other's nearest;
// they are merged and the chain goes on from the node before them. Two mutual nearest
// neighbours are merged by the greedy order too, whenever they are found: a node's distance to
// a merged one is never below its distance to either part (the union's sphere holds both), so
// no later merge comes between them (up to rounding). Fewer searches than a heap of every
// node's nearest neighbour, whose entries go stale and are searched again; single thread,
// ties broken by node index, so the tree depends on the lights alone. The finished tree is
// laid out depth first (node 0 is the root), its copy of the lights in the order of the
// leaves.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/lights/light.hpp>
#include <glint/lights/light_bounds.hpp>
#include <glint/lights/sphere_neighbours.hpp>

namespace glint {

/// Which lights the tree merges first. spatial: Fernandez 2004, §5.1.2's order, the closest
/// pair of all. by_orientation: the closest pair among the lights whose axes point to the same
/// face of the cube (isotropic lights apart), then the groups' roots: a node then mixes
/// orientations only near the root, the role Walter et al. 2005's orientation term plays in
/// its clustering metric.
enum class ClusterGrouping : std::uint8_t { spatial, by_orientation };

/// One node of the cluster tree; a leaf's representative is its light.
template <Scalar T>
struct LightNode {
    static constexpr std::uint32_t none = 0xffffffffu;  ///< No node: a leaf's children, the root's parent.
    AABB<T> box;                ///< Box of the lights' positions (world space).
    Rgb<T> intensity{T(0)};     ///< Sum of the lights' intensities (along their axes), W/sr per band.
    Vec3<T> axis{0, 0, 1};      ///< Unit axis of the orientation cone.
    T theta_o = pi<T>;          ///< Every light's axis lies within theta_o (radians) of `axis`; pi: any.
    T theta_e = pi<T>;          ///< No light emits beyond theta_e (radians) from its own axis.
    /// cos(theta_o), precomputed for the cuts' bounds.
    T cos_o = T(-1), sin_o = T(0), cos_e = T(-1);
    /// \var sin_o
    /// sin(theta_o), likewise.
    /// \var cos_e
    /// cos(theta_e), likewise.
    std::uint32_t rep = 0;      ///< Representative light: index into LightClusterTree::lights().
    std::uint32_t left = none;  ///< Left child's node index (none: a leaf).
    std::uint32_t right = none; ///< Right child's node index (none: a leaf).
    bool cosine = false;        ///< Every light has the cosine profile (PointLightKind::cosine).
    Vec3<T> centroid{0};        ///< Power-weighted mean of the lights' positions (a leaf: its light's).
    Vec3<T> mean_axis{0, 0, 1}; ///< Unit power-weighted mean of the lights' axes (a leaf: its light's).

    /// True for a leaf (one light, no children).
    bool leaf() const { return left == none; }
};

/// The light cluster tree of Fernandez 2004, §5.1.2: a binary tree over point lights, built by
/// greedy merging of the closest pair, laid out depth first (node 0 the root) and immutable once
/// built; cuts (lights/cuts.hpp) read it from any number of threads.
template <Scalar T>
class LightClusterTree {
public:
    using Node = LightNode<T>;  ///< A node of the tree.

    LightClusterTree() = default;
    /// Builds the tree over `lights` (validated first); an empty set gives an empty tree.
    /// ClusterGrouping::by_orientation merges within each orientation group first.
    explicit LightClusterTree(std::vector<PointLight<T>> lights, ClusterGrouping grouping = ClusterGrouping::spatial)
        : lights_(std::move(lights)), grouping_(grouping) {
        for (std::size_t i = 0; i < lights_.size(); ++i) lights_[i].validate(i);
        if (lights_.size() >= std::size_t(LightNode<T>::none / 2))
            throw Error("glint::LightClusterTree: " + std::to_string(lights_.size()) + " lights are too many");
        const auto start = std::chrono::steady_clock::now();
        build();
        build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }

    /// The tree's copy of the lights, in the order of its leaves (a node's `rep` indexes it).
    std::span<const PointLight<T>> lights() const { return lights_; }
    /// All nodes, depth first: 2n - 1 for n lights, none for an empty tree.
    std::span<const Node> nodes() const { return nodes_; }
    /// Node i (unchecked: i < nodes().size()).
    const Node& node(std::uint32_t i) const { return nodes_[i]; }
    /// True when the tree was built over no lights (it has no root then).
    bool empty() const { return nodes_.empty(); }
    /// The root's index: always 0 (valid only when !empty()).
    std::uint32_t root() const { return 0; }
    /// Wall-clock seconds the build took (0 for a default-constructed tree).
    double build_seconds() const { return build_seconds_; }
    /// The tree's memory: its nodes and its copy of the lights.
    std::size_t bytes() const { return nodes_.capacity() * sizeof(Node) + lights_.capacity() * sizeof(PointLight<T>); }

private:
    static Node leaf_node(const PointLight<T>& l, std::uint32_t i) {
        Node n;
        n.box.extend(l.position);
        n.intensity = l.intensity;
        n.rep = i;
        n.axis = l.axis;
        n.centroid = l.position;
        n.mean_axis = l.axis;
        n.cosine = l.kind == PointLightKind::cosine;
        n.theta_o = l.kind == PointLightKind::isotropic ? pi<T> : T(0);
        n.theta_e = l.kind == PointLightKind::isotropic ? pi<T> : std::acos(std::clamp(l.cos_emission(), T(-1), T(1)));
        return with_cosines(n);
    }

    /// Node c as the union of nodes a and b.
    Node merged(std::uint32_t a, std::uint32_t b) const {
        const Node &na = nodes_[a], &nb = nodes_[b];
        Node n;
        n.box = na.box;
        n.box.extend(nb.box);
        n.intensity = na.intensity + nb.intensity;
        const DirectionCone<T> cone =
            cone_union(DirectionCone<T>{na.axis, std::cos(na.theta_o)}, DirectionCone<T>{nb.axis, std::cos(nb.theta_o)});
        n.axis = cone.w;
        // Widened by a few ulps, so that it bounds its inputs under rounding.
        n.theta_o = cone.cos_theta <= T(-1) ? pi<T> : std::min(pi<T>, std::acos(cone.cos_theta) + T(1e-5));
        n.theta_e = std::max(na.theta_e, nb.theta_e);
        n.cosine = na.cosine && nb.cosine;
        n.left = a;
        n.right = b;
        // The representative closer to the power-weighted centroid (the box's centre if dark).
        const T w = weight_[a] + weight_[b];
        const Vec3<T> centroid = w > T(0) ? (moment_[a] + moment_[b]) / w : n.box.center();
        const Vec3<T> pa = lights_[na.rep].position, pb = lights_[nb.rep].position;
        n.rep = glm::dot(pb - centroid, pb - centroid) < glm::dot(pa - centroid, pa - centroid) ? nb.rep : na.rep;
        n.centroid = centroid;
        const Vec3<T> axes = axis_moment_[a] + axis_moment_[b];
        n.mean_axis = glm::dot(axes, axes) > T(0) ? glm::normalize(axes) : n.axis;
        return with_cosines(n);
    }

    static Node with_cosines(Node n) {
        n.cos_o = std::cos(n.theta_o);
        n.sin_o = std::sin(n.theta_o);
        n.cos_e = std::cos(n.theta_e);
        return n;
    }

    void build() {
        const std::uint32_t n = std::uint32_t(lights_.size());
        if (n == 0) return;
        const std::size_t total = 2 * std::size_t(n) - 1;
        nodes_.reserve(total);
        spheres_.reserve(total);
        weight_.reserve(total);
        moment_.reserve(total);
        axis_moment_.reserve(total);
        for (std::uint32_t i = 0; i < n; ++i) {
            nodes_.push_back(leaf_node(lights_[i], i));
            spheres_.push_back({lights_[i].position, T(0)});
            weight_.push_back(lights_[i].power().luminance());
            moment_.push_back(lights_[i].position * weight_.back());
            axis_moment_.push_back(lights_[i].axis * weight_.back());
        }
        std::vector<char> merged_away(2 * std::size_t(n) - 1, 0);
        std::vector<std::uint32_t> roots;
        for (std::vector<std::uint32_t>& group : groups())
            roots.push_back(merge_all(std::move(group), merged_away));
        merge_all(std::move(roots), merged_away);
        std::vector<BoundingSphere<T>>().swap(spheres_);
        std::vector<T>().swap(weight_);
        std::vector<Vec3<T>>().swap(moment_);
        std::vector<Vec3<T>>().swap(axis_moment_);
        depth_first_layout();
    }

    /// The leaves' groups, each in light order: one group (ClusterGrouping::spatial), or one
    /// per face of the cube the lights' axes point to and one of the isotropic lights.
    std::vector<std::vector<std::uint32_t>> groups() const {
        const std::uint32_t n = std::uint32_t(lights_.size());
        std::vector<std::vector<std::uint32_t>> out(grouping_ == ClusterGrouping::spatial ? 1 : 7);
        for (std::uint32_t i = 0; i < n; ++i) {
            const PointLight<T>& l = lights_[i];
            std::size_t g = 0;
            if (grouping_ == ClusterGrouping::by_orientation) {
                const Vec3<T> a = glm::abs(l.axis);
                const int k = a.x >= a.y && a.x >= a.z ? 0 : a.y >= a.z ? 1 : 2;
                g = l.kind == PointLightKind::isotropic ? 6 : std::size_t(2 * k + (l.axis[k] < T(0)));
            }
            out[g].push_back(i);
        }
        std::erase_if(out, [](const auto& g) { return g.empty(); });
        return out;
    }

    /// Merges the closest two parentless nodes among `ids` (and the nodes made of them) until
    /// one is left; returns it. A chain of nearest neighbours is walked from a live node until
    /// its last two are each other's nearest (a tie goes to the one before), which are merged;
    /// the walk goes on from the chain's rest.
    std::uint32_t merge_all(std::vector<std::uint32_t> ids, std::vector<char>& merged_away) {
        if (ids.size() == 1) return ids[0];
        SphereNeighbours<T> nn(spheres_, ids);
        std::vector<std::uint32_t> chain, start(ids.rbegin(), ids.rend());  // start: where a new chain may begin
        for (std::size_t live = ids.size(); live > 1;) {
            if (chain.empty()) {
                while (merged_away[start.back()]) start.pop_back();
                chain.push_back(start.back());
            }
            const std::uint32_t a = chain.back();
            const auto near = nn.nearest(a);
            const std::uint32_t before = chain.size() >= 2 ? chain[chain.size() - 2] : LightNode<T>::none;
            if (before == LightNode<T>::none || cluster_distance(spheres_[a], spheres_[before]) > near.distance) {
                chain.push_back(near.id);
                continue;
            }
            chain.resize(chain.size() - 2);
            merge(std::min(a, before), std::max(a, before), nn, merged_away);
            start.push_back(std::uint32_t(nodes_.size() - 1));
            --live;
        }
        return std::uint32_t(nodes_.size() - 1);
    }

    /// Nodes in depth-first order (the root first, a left child right after its parent) and the
    /// lights in the order of their leaves, so that a subtree's nodes and lights are contiguous
    /// in memory: a cut reads nearby nodes and representatives. Both arrays are permuted in
    /// place (no second copy of the tree to allocate and fault in).
    void depth_first_layout() {
        std::vector<std::uint32_t> node_at(nodes_.size()), light_at(lights_.size());
        std::uint32_t next_node = 0, next_light = 0;
        std::vector<std::uint32_t> stack{std::uint32_t(nodes_.size() - 1)};
        while (!stack.empty()) {
            const std::uint32_t k = stack.back();
            stack.pop_back();
            node_at[k] = next_node++;
            if (nodes_[k].leaf()) {
                light_at[nodes_[k].rep] = next_light++;
                continue;
            }
            stack.push_back(nodes_[k].right);
            stack.push_back(nodes_[k].left);
        }
        for (Node& n : nodes_) {
            n.rep = light_at[n.rep];
            if (!n.leaf()) n.left = node_at[n.left], n.right = node_at[n.right];
        }
        permute(nodes_, node_at);
        permute(lights_, light_at);
    }

    /// Moves v[i] to v[to[i]] for every i, in place by following the permutation's cycles
    /// (`to` is left as the identity).
    template <class U>
    static void permute(std::vector<U>& v, std::vector<std::uint32_t>& to) {
        for (std::uint32_t i = 0; i < std::uint32_t(v.size()); ++i)
            while (to[i] != i) {
                const std::uint32_t j = to[i];
                std::swap(v[i], v[j]);
                std::swap(to[i], to[j]);
            }
    }

    void merge(std::uint32_t a, std::uint32_t b, SphereNeighbours<T>& nn, std::vector<char>& merged_away) {
        nodes_.push_back(merged(a, b));
        spheres_.push_back(enclosing_sphere(spheres_[a], spheres_[b]));
        weight_.push_back(weight_[a] + weight_[b]);
        moment_.push_back(moment_[a] + moment_[b]);
        axis_moment_.push_back(axis_moment_[a] + axis_moment_[b]);
        merged_away[a] = merged_away[b] = 1;
        nn.remove(a);
        nn.remove(b);
        nn.insert(std::uint32_t(nodes_.size() - 1));
    }

    std::vector<PointLight<T>> lights_;
    ClusterGrouping grouping_ = ClusterGrouping::spatial;
    std::vector<Node> nodes_;
    double build_seconds_ = 0;
    // Build scratch, released after the build.
    std::vector<BoundingSphere<T>> spheres_;
    std::vector<T> weight_;
    std::vector<Vec3<T>> moment_, axis_moment_;  // per node: sum of power times position, times axis
};

}  // namespace glint
