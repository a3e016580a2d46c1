// glint/lights/light_tree.hpp: the stochastic light tree (Conty Estevez and Kulla 2018): a
// binary BVH over emitters whose nodes hold LightBounds (lights/light_bounds.hpp); a light is
// picked for a shading point by descending from the root, choosing each child in proportion to
// its importance there, so that lights that cannot matter at the point are rarely or never
// chosen, and its probability is the product of the choices. Unbiased wherever importance is
// positive for every light that can light the point, which the bounds guarantee.
//
// Built top-down: at each node the emitters' centroids are binned (12 buckets per axis) and
// the split of least cost phi M_Omega area Kr summed over both sides is taken (the paper's
// orientation-aware cost, §4.3, as pbrt-v4's BVHLightSampler evaluates it; M_Omega measures
// the node's two cones, Kr penalizes thin splits). The build is sequential, so the tree is a
// function of its input alone. One emitter per leaf; nodes in depth-first order.
//
//   LightTree<float> tree(bounds);          // bounds[i]: emitter i (scene_light_bounds(scene))
//   auto [light, p] = tree.pick(x, n, u);   // p = 0: nothing can light x (light is undefined)
//   float q = tree.probability(x, n, light);  // the same p, for MIS
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/lights/importance_pair.hpp>
#include <glint/lights/light_bounds.hpp>

namespace glint {

/// A light chosen for a shading point and the probability it was chosen with.
template <Scalar T>
struct LightPick {
    std::size_t index = 0;  ///< The emitter's index in the tree's input (undefined when probability is 0).
    T probability = T(0);   ///< Probability it was picked with; 0: no light can reach the point.
};

/// The stochastic light tree of Conty Estevez and Kulla 2018 over emitters' bounds: immutable
/// once built; pick() and probability() are const and safe to call from any number of threads.
template <Scalar T = float>
class LightTree {
public:
    /// A node, in depth-first order (node 0 the root).
    struct Node {
        LightBounds<T> bounds;     ///< Bounds of the emitters below the node.
        std::int32_t second = -1;  ///< Interior: the second child (the first follows the node); leaf: -1.
        std::int32_t light = -1;   ///< Leaf: the emitter's index.
        std::int32_t parent = -1;  ///< The parent's index; -1 at the root.
    };

    LightTree() = default;
    /// Throws glint::Error naming the first emitter with non-finite bounds or a negative phi.
    explicit LightTree(std::span<const LightBounds<T>> emitters) {
        for (std::size_t i = 0; i < emitters.size(); ++i) check(emitters[i], i);
        if (emitters.size() > std::size_t(std::numeric_limits<std::int32_t>::max() / 2))
            throw Error("LightTree: " + std::to_string(emitters.size()) + " emitters are too many");
        std::vector<std::uint32_t> order(emitters.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = std::uint32_t(i);
        leaf_of_.assign(emitters.size(), -1);
        nodes_.reserve(2 * emitters.size());
        if (!emitters.empty()) build(emitters, order, 0, order.size(), -1);
        descent_.reserve(nodes_.size());
        for (const Node& nd : nodes_) descent_.push_back({CompactLightBounds<T>(nd.bounds), nd.second});
    }

    /// True for a tree over no emitters (pick() then returns probability 0).
    bool empty() const { return nodes_.empty(); }
    /// Number of emitters.
    std::size_t size() const { return leaf_of_.size(); }
    /// All nodes, depth first: 2n - 1 for n emitters.
    const std::vector<Node>& nodes() const { return nodes_; }
    /// The tree's memory: its nodes, their compact descent form and the emitters' leaf indices.
    std::size_t bytes() const {
        return nodes_.size() * (sizeof(Node) + sizeof(DescentNode)) + leaf_of_.size() * sizeof(std::int32_t);
    }

    /// A light for point x with normal n (0: none) by u in [0, 1), and its probability; 0
    /// where no light can reach x.
    LightPick<T> pick(const Vec3<T>& x, const Vec3<T>& n, T u) const {
        if (nodes_.empty()) return {};
        std::size_t i = 0;
        T p = T(1);
        while (descent_[i].second >= 0) {
            const std::size_t c0 = i + 1, c1 = std::size_t(descent_[i].second);
            const auto [i0, i1] = importance_pair(descent_[c0].bounds, descent_[c1].bounds, x, n);
            const T sum = i0 + i1;
            // Neither child can reach x; or x is on a point light (importance infinite), where
            // probability() finds 0/0 too.
            if (!(sum > T(0)) || !(sum <= std::numeric_limits<T>::max())) return {};
            // The choice compares u sum with i0, so that the next node does not wait on a
            // division; the probability and the rescaled u are off that path.
            const T us = u * sum, p0 = i0 / sum;
            if (us < i0 || !(i1 > T(0))) {
                u = std::min(us / i0, one_minus_epsilon);
                p *= p0, i = c0;
            } else {
                u = std::min((us - i0) / i1, one_minus_epsilon);
                p *= T(1) - p0, i = c1;
            }
        }
        return {std::size_t(nodes_[i].light), p};
    }

    /// The probability that pick(x, n, u) returns `light` for u uniform in [0, 1).
    T probability(const Vec3<T>& x, const Vec3<T>& n, std::size_t light) const {
        if (light >= leaf_of_.size()) return T(0);
        T p = T(1);
        for (std::int32_t i = leaf_of_[light]; nodes_[std::size_t(i)].parent >= 0;) {
            const std::size_t parent = std::size_t(nodes_[std::size_t(i)].parent);
            const T p0 = first_share(x, n, parent + 1, std::size_t(descent_[parent].second));
            if (!(p0 >= T(0))) return T(0);
            p *= std::size_t(i) == parent + 1 ? p0 : T(1) - p0;
            i = std::int32_t(parent);
        }
        return p;
    }

    /// Whether two trees have the same nodes, bit for bit.
    bool operator==(const LightTree& o) const {
        auto same = [](const Node& a, const Node& b) {
            const LightBounds<T>&p = a.bounds, &q = b.bounds;
            return a.second == b.second && a.light == b.light && a.parent == b.parent && p.box.lo == q.box.lo &&
                   p.box.hi == q.box.hi && p.phi == q.phi && p.w == q.w && p.cos_theta_o == q.cos_theta_o &&
                   p.cos_theta_e == q.cos_theta_e;
        };
        return leaf_of_ == o.leaf_of_ && std::equal(nodes_.begin(), nodes_.end(), o.nodes_.begin(), o.nodes_.end(), same);
    }

private:
    static constexpr int buckets = 12;
    static constexpr T one_minus_epsilon = T(1) - std::numeric_limits<T>::epsilon() / T(2);

    static void check(const LightBounds<T>& b, std::size_t i) {
        const bool finite = all_finite(b.box.lo) && all_finite(b.box.hi) && std::isfinite(double(b.phi)) && all_finite(b.w);
        if (!finite || b.phi < T(0) || b.box.empty())
            throw Error("LightTree: emitter " + std::to_string(i) + " has non-finite or empty bounds or a negative power");
    }

    /// The first child's share of the two children's importance at x; -1 if both are 0.
    T first_share(const Vec3<T>& x, const Vec3<T>& n, std::size_t c0, std::size_t c1) const {
        const auto [i0, i1] = importance_pair(descent_[c0].bounds, descent_[c1].bounds, x, n);
        if (!(i0 + i1 > T(0))) return T(-1);
        return i0 / (i0 + i1);
    }

    /// The paper's orientation measure M_Omega of a node's cones.
    static T orientation_measure(const LightBounds<T>& b) {
        const T theta_o = detail::safe_acos(b.cos_theta_o), theta_e = detail::safe_acos(b.cos_theta_e);
        const T theta_w = std::min(theta_o + theta_e, pi<T>);
        const T sin_o = detail::sin_from_cos(b.cos_theta_o);
        return T(2) * pi<T> * (T(1) - b.cos_theta_o) +
               pi<T> / T(2) * (T(2) * theta_w * sin_o - std::cos(theta_o - T(2) * theta_w) - T(2) * theta_o * sin_o + b.cos_theta_o);
    }
    /// A side's cost; a point cluster's zero area is floored at a small share of its parent's,
    /// so that splitting off single point lights is not free.
    static T cost(const LightBounds<T>& b, T area_floor) {
        if (!(b.phi > T(0))) return T(0);
        return b.phi * orientation_measure(b) * std::max(b.box.surface_area(), area_floor);
    }

    struct Split {
        int axis = -1;
        T at = T(0);  // centroids below go left
        T cost = infinity<T>;
    };

    /// The least-cost bucket split of order[begin, end) over the three axes.
    static Split best_split(std::span<const LightBounds<T>> e, const std::vector<std::uint32_t>& order, std::size_t begin,
                            std::size_t end, const LightBounds<T>& node) {
        AABB<T> cbox;
        for (std::size_t k = begin; k < end; ++k) cbox.extend(e[order[k]].box.center());
        const Vec3<T> ext = node.box.extent();
        const T max_ext = std::max({ext.x, ext.y, ext.z}), floor = node.box.surface_area() * T(1e-4);
        Split best;
        for (int a = 0; a < 3; ++a) {
            const T lo = cbox.lo[a], width = cbox.hi[a] - cbox.lo[a];
            if (!(width > T(0))) continue;
            std::array<LightBounds<T>, buckets> bucket{};
            for (std::size_t k = begin; k < end; ++k) {
                const int bi = std::min(buckets - 1, int(T(buckets) * (e[order[k]].box.center()[a] - lo) / width));
                bucket[std::size_t(bi)] = bounds_union(bucket[std::size_t(bi)], e[order[k]]);
            }
            const T kr = ext[a] > T(0) ? max_ext / ext[a] : T(1);
            std::array<LightBounds<T>, buckets> right{};  // right[s]: buckets s.. together
            for (int k = buckets - 1; k > 0; --k)
                right[std::size_t(k)] = bounds_union(bucket[std::size_t(k)], k + 1 < buckets ? right[std::size_t(k + 1)] : LightBounds<T>{});
            LightBounds<T> left;
            for (int s = 1; s < buckets; ++s) {
                left = bounds_union(left, bucket[std::size_t(s - 1)]);
                const T c = kr * (cost(left, floor) + cost(right[std::size_t(s)], floor));
                if (c < best.cost) best = {a, lo + width * T(s) / T(buckets), c};
            }
        }
        return best;
    }

    /// Builds the subtree of order[begin, end) as node nodes_.size(); returns its index.
    std::int32_t build(std::span<const LightBounds<T>> e, std::vector<std::uint32_t>& order, std::size_t begin,
                       std::size_t end, std::int32_t parent) {
        const auto self = std::int32_t(nodes_.size());
        LightBounds<T> b;
        for (std::size_t k = begin; k < end; ++k) b = bounds_union(b, e[order[k]]);
        if (b.box.empty()) b.box = e[order[begin]].box;  // only dark emitters
        nodes_.push_back(Node{b, -1, -1, parent});
        if (end - begin == 1) {
            nodes_.back().light = std::int32_t(order[begin]);
            leaf_of_[order[begin]] = self;
            return self;
        }
        const Split s = best_split(e, order, begin, end, b);
        std::size_t mid = begin + (end - begin) / 2;  // coincident centroids: halve the range
        if (s.axis >= 0) {
            const auto it = std::partition(order.begin() + std::ptrdiff_t(begin), order.begin() + std::ptrdiff_t(end),
                                           [&](std::uint32_t i) { return e[i].box.center()[s.axis] < s.at; });
            const auto m = std::size_t(it - order.begin());
            if (m > begin && m < end) mid = m;
        }
        build(e, order, begin, mid, self);
        const std::int32_t second = build(e, order, mid, end, self);
        nodes_[std::size_t(self)].second = second;
        return self;
    }

    /// What a descent reads of a node: its bounds in importance()'s form and its second child.
    struct DescentNode {
        CompactLightBounds<T> bounds;
        std::int32_t second;
    };

    std::vector<Node> nodes_;
    std::vector<DescentNode> descent_;  // per node, in the same order
    std::vector<std::int32_t> leaf_of_;  // per emitter: its leaf
};

}  // namespace glint
