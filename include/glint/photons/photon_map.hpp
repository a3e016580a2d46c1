// glint/photons/photon_map.hpp: the photon map as a left-balanced kd-tree (Jensen 2001, ch. 6;
// Larsen 2004, §4.3): a complete binary tree stored in heap order (node i's children are
// 2i + 1 and 2i + 2), so it needs no pointers; each node is a photon.
//
// Balancing (Jensen 2001, ch. 6): each subtree splits its photons on the axis of their
// bounding box's largest extent, at the element that makes the left subtree exactly as large
// as a left-balanced tree's (found by std::nth_element), and recurses: O(n log n).
//
// Query (Jensen 2001, ch. 6): the k nearest photons within a maximum radius R (distance <= R),
// found by a depth-first descent to the query's side with an explicit stack of the far
// sides still to visit, each with the squared distance from the query to its cell (Arya and
// Mount 1993's incremental distance: tighter than the distance to the splitting plane alone),
// skipped once that exceeds the current bound; a subtree of three levels or fewer is tested
// whole, without the stack. The found photons are collected unordered until k are
// there, then kept as a max-heap on squared distance, whose top bounds the search. Nodes are
// 16 bytes (position and split axis), kept apart from the photons' payload so that a query
// reads four nodes per cache line.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/cache_line_allocator.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/photons/photon.hpp>

namespace glint {

/// A found photon: its squared distance to the query and its index in PhotonMap::photons().
struct PhotonNeighbour {
    float d2;              ///< Squared distance to the query point (scene units squared).
    std::uint32_t index;   ///< Index of the photon in PhotonMap::photons() (heap order).
};

/// The photon map: a left-balanced kd-tree over photons (Jensen 2001, ch. 6), immutable once
/// balanced; queries are const and safe from many threads, each with its own scratch vector.
class PhotonMap {
public:
    PhotonMap() = default;
    /// Balances `photons` into a left-balanced kd-tree (at most 2^32 - 1 photons).
    explicit PhotonMap(std::vector<Photon> photons) {
        if (photons.size() >= std::numeric_limits<std::uint32_t>::max())
            throw Error("glint::PhotonMap: " + std::to_string(photons.size()) + " photons exceed 2^32 - 1");
        std::vector<Entry> work(photons.size());
        for (std::size_t i = 0; i < photons.size(); ++i) work[i] = {photons[i].position, std::uint32_t(i)};
        nodes_.resize(photons.size() + 1);  // node j = photon j - 1: heap indices from 1
        photons_.resize(photons.size());
        if (!work.empty()) balance(work.data(), work.size(), 0, bounds(work), photons);
    }

    /// Number of photons.
    std::size_t size() const { return photons_.size(); }
    /// True for a map without photons (every query then finds none).
    bool empty() const { return photons_.empty(); }
    /// The photons in heap order: index i of a PhotonNeighbour.
    std::span<const Photon> photons() const { return photons_; }
    /// Photon i in heap order (unchecked: i < size()).
    const Photon& photon(std::size_t i) const { return photons_[i]; }

    /// The k nearest photons to x within distance max_radius (<= max_radius), into `out`
    /// (overwritten; its storage is reused, so a caller's vector makes queries allocation-free)
    /// as a max-heap on d2 when min(k, size()) were found (out.front(): the farthest),
    /// unordered when fewer were. Ties at the k-th distance are broken arbitrarily.
    void knn(const Vec3<float>& x, std::size_t k, float max_radius, std::vector<PhotonNeighbour>& out) const {
        nearest(x, k, max_radius, out, [](std::uint32_t) { return true; });
    }

    /// knn among the photons i for which accept(i) holds.
    template <class Accept>
    void nearest(const Vec3<float>& x, std::size_t k, float max_radius, std::vector<PhotonNeighbour>& out,
                 const Accept& accept) const {
        if (!(max_radius >= 0.0f)) throw Error("glint::PhotonMap::knn: max_radius must be >= 0 (got " + std::to_string(max_radius) + ")");
        if (k == 0 || photons_.empty()) return out.clear();
        k = std::min(k, photons_.size());
        if (out.size() < k) out.resize(k);  // written in place; shrunk to what was found below
        Bound b{std::nextafter(max_radius * max_radius, std::numeric_limits<float>::infinity()), k, out.data()};
        search(x, b, accept);
        out.resize(b.count);
    }

private:
    struct Node {
        float p[3];
        std::uint32_t axis;
    };
    struct Entry {
        Vec3<float> p;
        std::uint32_t index;
    };
    struct Box {
        Vec3<float> lo, hi;
    };
    /// The found set and its bound: all photons closer than `r2` until k are found, then a
    /// max-heap of k whose top is the bound.
    struct Bound {
        float r2;
        std::size_t k;
        PhotonNeighbour* heap;
        std::size_t count = 0;

        void add(float d2, std::uint32_t i) {
            if (count < k) {
                heap[count++] = {d2, i};
                if (count == k) {
                    std::make_heap(heap, heap + k, [](const PhotonNeighbour& a, const PhotonNeighbour& b) { return a.d2 < b.d2; });
                    r2 = heap[0].d2;
                }
                return;
            }
            sift_down({d2, i});
            r2 = heap[0].d2;
        }
        /// Replaces the heap's top by e and restores the heap.
        void sift_down(PhotonNeighbour e) {
            std::size_t i = 0;
            for (;;) {
                std::size_t c = 2 * i + 1;
                if (c >= k) break;
                if (c + 1 < k && heap[c + 1].d2 > heap[c].d2) ++c;
                if (heap[c].d2 <= e.d2) break;
                heap[i] = heap[c];
                i = c;
            }
            heap[i] = e;
        }
    };

    template <class Accept>
    void search(const Vec3<float>& x, Bound& b, const Accept& accept) const {
        struct Pending {
            std::uint32_t node;
            float d2;         // squared distance from x to the subtree's cell
            Vec3<float> off;  // its per-axis offsets
        };
        std::array<Pending, 64> stack;  // one far side per level: depth <= 32
        int top = 0;
        const auto end = std::uint32_t(nodes_.size());  // nodes 1 .. end - 1
        const Node* nodes = nodes_.data();
        std::uint32_t j = 1;
        float cell = 0.0f;           // squared distance from x to node j's cell
        Vec3<float> off(0.0f);       // per-axis distance from x to that cell
        for (;;) {
            while (j < end) {
                if (8 * j >= end) {  // at most two levels below: test them all, no stack
                    for (const std::uint32_t lo : {j, 2 * j, 4 * j})
                        for (std::uint32_t c = lo; c < std::min(end, lo + lo / j); ++c) {
                            const float dx = x.x - nodes[c].p[0], dy = x.y - nodes[c].p[1], dz = x.z - nodes[c].p[2];
                            const float d2 = dx * dx + dy * dy + dz * dz;
                            if (d2 < b.r2 && accept(c - 1)) b.add(d2, c - 1);
                        }
                    break;
                }
                const Node& nd = nodes[j];
                // With 64-byte aligned nodes of 16 bytes, node j's four grandchildren 4j ..
                // 4j + 3 fill one cache line: fetch it while this level is worked on.
                __builtin_prefetch(nodes + std::min(4 * j, end - 1));
                const float dx = x.x - nd.p[0], dy = x.y - nd.p[1], dz = x.z - nd.p[2];
                const float d2 = dx * dx + dy * dy + dz * dz;
                if (d2 < b.r2 && accept(j - 1)) b.add(d2, j - 1);
                const auto a = int(nd.axis);
                const float delta = x[a] - nd.p[a];
                const std::uint32_t near = 2 * j + (delta > 0.0f), far = 2 * j + (delta <= 0.0f);
                if (far < end) {
                    // Arya and Mount 1993's incremental distance: the far cell differs from
                    // this one on axis a only, where it lies |delta| away.
                    const float far_d2 = cell - off[a] * off[a] + delta * delta;
                    if (far_d2 < b.r2) {
                        Pending& p = stack[std::size_t(top++)];
                        p = {far, far_d2, off};
                        p.off[a] = delta;
                    }
                }
                j = near;
            }
            do {
                if (top == 0) return;
                --top;
            } while (stack[std::size_t(top)].d2 >= b.r2);
            const Pending& p = stack[std::size_t(top)];
            j = p.node, cell = p.d2, off = p.off;
        }
    }

    static Box bounds(std::span<const Entry> e) {
        Box b{e[0].p, e[0].p};
        for (const Entry& x : e) b.lo = glm::min(b.lo, x.p), b.hi = glm::max(b.hi, x.p);
        return b;
    }
    /// Size of the left subtree of a left-balanced tree of n nodes.
    static std::size_t left_size(std::size_t n) {
        if (n <= 1) return 0;
        int h = 0;
        while ((std::size_t(2) << h) <= n) ++h;  // 2^h <= n < 2^(h+1)
        const std::size_t full = (std::size_t(1) << h) - 1, last = n - full, half = std::size_t(1) << (h - 1);
        return (full - 1) / 2 + std::min(last, half);
    }
    void balance(Entry* e, std::size_t n, std::size_t heap, Box box, const std::vector<Photon>& src) {
        const Vec3<float> ext = box.hi - box.lo;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const std::size_t m = left_size(n);
        std::nth_element(e, e + m, e + n, [axis](const Entry& a, const Entry& b) { return a.p[axis] < b.p[axis]; });
        const Entry& med = e[m];
        nodes_[heap + 1] = {{med.p.x, med.p.y, med.p.z}, std::uint32_t(axis)};
        photons_[heap] = src[med.index];
        const float split = med.p[axis];
        if (m > 0) {
            Box l = box;
            l.hi[axis] = split;
            balance(e, m, 2 * heap + 1, l, src);
        }
        if (n - m - 1 > 0) {
            Box r = box;
            r.lo[axis] = split;
            balance(e + m + 1, n - m - 1, 2 * heap + 2, r, src);
        }
    }

    std::vector<Node, detail::CacheLineAllocator<Node>> nodes_;
    std::vector<Photon> photons_;
};

}  // namespace glint
