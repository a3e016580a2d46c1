// glint/lights/sample_neighbours.hpp: the k nearest surface samples of a point under Fernandez
// 2004's sample distance (§5.4.2, eq. 5.22)
//   d(x, s) = |x - s| / (n_x . n_s)  where n_x . n_s > 0,  infinite otherwise,
// which keeps samples of a differently oriented surface out of a point's neighbourhood. A
// kd-tree over the samples' positions (built once, read-only afterwards): since d >= |x - s|, a
// subtree whose box is farther (Euclidean) than the current k-th distance holds no better sample.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

#include <glint/core/math.hpp>

namespace glint {

/// One neighbour: the sample's index and its distance (eq. 5.22).
template <Scalar T>
struct SampleNeighbour {
    std::uint32_t sample;  ///< Index of the sample in the positions the tree was built over.
    T distance;            ///< Its eq. 5.22 distance from the query point (world units).
};

/// Eq. 5.22: the distance from point x of unit normal nx to sample s of unit normal ns.
template <Scalar T>
T sample_distance(const Vec3<T>& x, const Vec3<T>& nx, const Vec3<T>& s, const Vec3<T>& ns) {
    const T c = glm::dot(nx, ns);
    if (!(c > T(0))) return infinity<T>;
    return glm::length(x - s) / c;
}

/// A kd-tree over surface samples for k-nearest queries under the eq. 5.22 distance; it keeps
/// the positions and normals by reference (they must outlive it) and is read-only once built.
template <Scalar T>
class SampleNeighbours {
public:
    SampleNeighbours() = default;
    /// The kd-tree over `positions` (with their unit `normals`; both kept by reference).
    SampleNeighbours(std::span<const Vec3<T>> positions, std::span<const Vec3<T>> normals) : x_(positions), n_(normals) {
        order_.resize(x_.size());
        std::iota(order_.begin(), order_.end(), std::uint32_t(0));
        if (!order_.empty()) build(0, std::uint32_t(order_.size()));
    }

    /// The (at most) k samples nearest to x (normal nx) within `radius`, nearest first, into
    /// `out` (cleared first).
    void nearest(const Vec3<T>& x, const Vec3<T>& nx, int k, T radius, std::vector<SampleNeighbour<T>>& out) const {
        out.clear();
        if (order_.empty() || k <= 0) return;
        search(0, std::uint32_t(order_.size()), x, nx, std::size_t(k), radius, out);
    }

private:
    static constexpr std::uint32_t bucket = 8;

    struct Node {
        T split;
        int axis;
    };

    /// Median split of order_[b, e) on its widest axis; a node per range of more than `bucket`,
    /// kept at index (b + e) / 2 of nodes_ (ranges are disjoint, so indices are unique).
    void build(std::uint32_t b, std::uint32_t e) {
        if (e - b <= bucket) return;
        Vec3<T> lo(infinity<T>), hi(-infinity<T>);
        for (std::uint32_t i = b; i < e; ++i) {
            lo = glm::min(lo, x_[order_[i]]);
            hi = glm::max(hi, x_[order_[i]]);
        }
        const Vec3<T> ext = hi - lo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const std::uint32_t m = (b + e) / 2;
        std::nth_element(order_.begin() + b, order_.begin() + m, order_.begin() + e,
                         [&](std::uint32_t p, std::uint32_t q) { return x_[p][axis] < x_[q][axis] || (x_[p][axis] == x_[q][axis] && p < q); });
        if (nodes_.size() < order_.size()) nodes_.resize(order_.size());
        nodes_[m] = Node{x_[order_[m]][axis], axis};
        build(b, m);
        build(m, e);
    }

    /// The current bound: the k-th distance once k are found, else the radius.
    static T bound(const std::vector<SampleNeighbour<T>>& out, std::size_t k, T radius) {
        return out.size() == k ? out.back().distance : radius;
    }

    void search(std::uint32_t b, std::uint32_t e, const Vec3<T>& x, const Vec3<T>& nx, std::size_t k, T radius,
                std::vector<SampleNeighbour<T>>& out) const {
        if (e - b <= bucket) {
            for (std::uint32_t i = b; i < e; ++i) offer(order_[i], x, nx, k, radius, out);
            return;
        }
        const std::uint32_t m = (b + e) / 2;
        const Node& node = nodes_[m];
        const T delta = x[node.axis] - node.split;
        const bool right_first = delta >= T(0);
        if (right_first) search(m, e, x, nx, k, radius, out);
        else search(b, m, x, nx, k, radius, out);
        if (std::abs(delta) <= bound(out, k, radius)) {
            if (right_first) search(b, m, x, nx, k, radius, out);
            else search(m, e, x, nx, k, radius, out);
        }
    }

    /// Sample i into the sorted list of the k nearest (ties: the smaller index first).
    void offer(std::uint32_t i, const Vec3<T>& x, const Vec3<T>& nx, std::size_t k, T radius,
               std::vector<SampleNeighbour<T>>& out) const {
        const T d = sample_distance(x, nx, x_[i], n_[i]);
        if (!(d <= radius)) return;
        const auto before = [](const SampleNeighbour<T>& a, const SampleNeighbour<T>& b) {
            return a.distance < b.distance || (a.distance == b.distance && a.sample < b.sample);
        };
        const SampleNeighbour<T> s{i, d};
        if (out.size() == k && !before(s, out.back())) return;
        if (out.size() == k) out.pop_back();
        out.insert(std::upper_bound(out.begin(), out.end(), s, before), s);
    }

    std::span<const Vec3<T>> x_, n_;
    std::vector<std::uint32_t> order_;
    std::vector<Node> nodes_;
};

}  // namespace glint
