// glint/trees/bvh_builder.hpp: binned SAH bounding volume hierarchy over primitive boxes.
//
// Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies" (IEEE RT 2007): at
// every node the primitives' box centres are binned along each axis (here 16 bins), the
// surface area heuristic is evaluated at every bin boundary in one sweep per axis, and the
// primitives are partitioned in place at the cheapest boundary. The heuristic:
//   cost(split) = C_T + C_I (SA(L) blocks(N_L) + SA(R) blocks(N_R)) / SA(node),
//   cost(leaf)  = C_I blocks(N),   blocks(n) = ceil(n / leaf_block),
// counting leaf cost per started block of `leaf_block` primitives, as leaves are tested a
// SIMD batch at a time (Embree counts its Triangle4 blocks the same way). A node becomes a
// leaf when that is not dearer and it holds at most `max_leaf` primitives.
//
// The result is a binary tree whose node slots are assigned from the primitive ranges, not
// from the order of work: a node over n primitives at slot s has its left child at s + 1
// and its right child at s + 2 n_L (a subtree over n primitives needs at most 2n - 1 slots).
// So subtrees built by different threads never share an allocator, and the tree (every
// slot, every primitive order) is the same for any thread count. The wide collapse
// (wide_bvh.hpp) reads it from the root.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>

namespace glint {

/// Where the wide collapse (wide_bvh.hpp) puts a node's children in the node array: each
/// child's subtree right after it (depth first), or a node's inner children side by side in
/// one block, then their subtrees (000 §4.4's idea of placing a node's children together).
enum class WideNodeOrder { depth_first, sibling_blocks };

/// Cost constants and limits of the binned SAH build (docs/trees.md: how they were chosen).
struct BvhBuildOptions {
    float traversal_cost = 1.0f;     // C_T, per binary node
    float intersection_cost = 1.0f;  // C_I, per started leaf block
    std::uint32_t leaf_block = 8;    // primitives tested together (the batch kernel's width)
    std::uint32_t max_leaf = 16;     // at most this many primitives per leaf (1 ... 16)
    std::uint32_t bins = 16;         // centre bins per axis (2 ... 64)
    unsigned threads = 1;            // build threads; 0: std::thread::hardware_concurrency()
    WideNodeOrder node_order = WideNodeOrder::depth_first;  // the wide nodes' order in memory

    void check() const {
        auto bad = [](const std::string& what) { throw Error("BvhBuildOptions: " + what); };
        if (!(traversal_cost >= 0) || !(intersection_cost > 0) || !std::isfinite(traversal_cost) ||
            !std::isfinite(intersection_cost))
            bad("costs must be finite, traversal_cost >= 0 and intersection_cost > 0 (got " +
                std::to_string(traversal_cost) + ", " + std::to_string(intersection_cost) + ")");
        if (leaf_block < 1 || max_leaf < 1 || max_leaf > 16)
            bad("leaf_block >= 1 and max_leaf in 1 ... 16 (got " + std::to_string(leaf_block) + ", " +
                std::to_string(max_leaf) + ")");
        if (bins < 2 || bins > 64) bad("bins in 2 ... 64 (got " + std::to_string(bins) + ")");
    }
    unsigned thread_count() const {
        return threads ? threads : std::max(1u, std::thread::hardware_concurrency());
    }
};

/// One slot of the binary tree. A leaf has right == 0 (slot 0 is the root, never a child).
struct BinaryBvhNode {
    AABB<float> box;
    std::uint32_t begin = 0, count = 0;  // primitive range (a leaf's contents, an inner node's span)
    std::uint32_t right = 0;             // inner: the right child's slot; the left one is this slot + 1
    bool leaf() const { return right == 0; }
};

/// The binned SAH tree: `nodes` has 2n - 1 slots for n primitives (unused slots stay
/// default); `prims` is the primitive order, leaf ranges index it.
struct BinaryBvh {
    std::vector<BinaryBvhNode> nodes;
    std::vector<std::uint32_t> prims;
    bool empty() const { return prims.empty(); }
};

namespace detail {

/// The cheapest bin boundary found at a node: axis (-1: none, all centres coincide), the
/// first bin of the right side, the normalized cost and the two sides' boxes.
struct SahSplit {
    int axis = -1;
    std::uint32_t bin = 0;
    float cost = infinity<float>;
    AABB<float> left, right;
};

/// The recursive build (Wald 2007); one object per build, shared by its threads. Each
/// node reads and permutes only its own range of `prims` and writes only its own slots.
class BinnedSah {
public:
    BinnedSah(std::span<const AABB<float>> boxes, std::span<const Vec3f> centres, const BvhBuildOptions& opt,
              BinaryBvh& out)
        : boxes_(boxes), centres_(centres), opt_(opt), out_(out), tokens_(int(opt.thread_count()) - 1) {}

    void node(std::uint32_t slot, std::uint32_t b, std::uint32_t e, const AABB<float>& box) {
        BinaryBvhNode& nd = out_.nodes[slot];
        nd.box = box;
        nd.begin = b;
        nd.count = e - b;
        const std::uint32_t n = e - b;
        if (n == 1) return;
        AABB<float> cbox;
        for (std::uint32_t i = b; i < e; ++i) cbox.extend(centre(prims()[i]));
        const Vec3f k = scales(cbox);
        const SahSplit s = find_split(b, e, cbox, k, box.surface_area());
        if (n <= opt_.max_leaf && !(s.cost < opt_.intersection_cost * float(blocks(n)))) return;
        std::uint32_t m = b + n / 2;
        AABB<float> lb, rb;
        if (s.axis >= 0) {
            const float lo = cbox.lo[s.axis], ka = k[s.axis];
            const auto mid = std::partition(prims().begin() + b, prims().begin() + e, [&](std::uint32_t p) {
                return bin_of(centre(p)[s.axis], lo, ka) < s.bin;
            });
            m = std::uint32_t(mid - prims().begin());
            lb = s.left;
            rb = s.right;
        } else {  // every centre is the same point: any halving is as good
            for (std::uint32_t i = b; i < m; ++i) lb.extend(boxes_[prims()[i]]);
            for (std::uint32_t i = m; i < e; ++i) rb.extend(boxes_[prims()[i]]);
        }
        nd.right = slot + 2 * (m - b);
        recurse(slot + 1, b, m, lb, nd.right, e, rb);
    }

private:
    std::vector<std::uint32_t>& prims() { return out_.prims; }
    Vec3f centre(std::uint32_t p) const { return centres_[p]; }
    std::uint32_t blocks(std::uint32_t n) const { return (n + opt_.leaf_block - 1) / opt_.leaf_block; }
    /// Bins per unit of centre coordinate on each axis (0 where all centres coincide).
    Vec3f scales(const AABB<float>& cbox) const {
        Vec3f k;
        for (int a = 0; a < 3; ++a) {
            const float ext = cbox.hi[a] - cbox.lo[a];
            k[a] = float(opt_.bins) * (1.0f - 0x1p-20f) / ext;
            if (!(ext > 0) || !std::isfinite(k[a])) k[a] = 0.0f;
        }
        return k;
    }
    /// The bin of a centre coordinate; the binning and the partition call this same code.
    std::uint32_t bin_of(float c, float lo, float k) const {
        return std::uint32_t(std::min(float(opt_.bins - 1), std::max(0.0f, (c - lo) * k)));
    }

    /// Runs the two children, the left one on a thread of its own when the subtree is
    /// large and a thread is free (the tree does not depend on which runs where). A thread
    /// gives its token back as soon as its subtree is done, and so does the waiting parent
    /// until the join, so that the side still at work can split its own large subtrees off
    /// again (uneven splits).
    void recurse(std::uint32_t ls, std::uint32_t b, std::uint32_t m, const AABB<float>& lb, std::uint32_t rs,
                 std::uint32_t e, const AABB<float>& rb) {
        constexpr std::uint32_t parallel_min = 4096;
        if (e - b >= parallel_min && tokens_.fetch_sub(1) > 0) {
            std::thread left([&] {
                node(ls, b, m, lb);
                tokens_.fetch_add(1);
            });
            node(rs, m, e, rb);
            tokens_.fetch_add(1);  // this thread waits: another may run meanwhile
            left.join();
            tokens_.fetch_sub(1);
            return;
        }
        if (e - b >= parallel_min) tokens_.fetch_add(1);
        node(ls, b, m, lb);
        node(rs, m, e, rb);
    }

    /// Bins every primitive of the range on the three axes in one pass, then sweeps each
    /// axis for its cheapest boundary (Wald 2007).
    SahSplit find_split(std::uint32_t b, std::uint32_t e, const AABB<float>& cbox, const Vec3f& k, float area) const {
        constexpr int max_bins = 64;
        AABB<float> bin_box[3][max_bins];
        std::uint32_t bin_n[3][max_bins] = {};
        for (std::uint32_t i = b; i < e; ++i) {
            const std::uint32_t p = out_.prims[i];
            const Vec3f c = centre(p);
            for (int a = 0; a < 3; ++a) {
                const std::uint32_t j = bin_of(c[a], cbox.lo[a], k[a]);
                bin_box[a][j].extend(boxes_[p]);
                ++bin_n[a][j];
            }
        }
        SahSplit best;
        const float inv_area = 1.0f / std::max(area, std::numeric_limits<float>::min());
        for (int a = 0; a < 3; ++a)
            if (k[a] != 0.0f) sweep(a, bin_box[a], bin_n[a], e - b, inv_area, best);
        return best;
    }

    /// The cheapest boundary on axis a, if cheaper than `best`: suffix costs right to left,
    /// then prefixes left to right.
    void sweep(int a, const AABB<float>* bin_box, const std::uint32_t* bin_n, std::uint32_t n, float inv_area,
               SahSplit& best) const {
        float right_cost[64];
        AABB<float> acc;
        std::uint32_t cnt = 0;
        for (std::uint32_t j = opt_.bins - 1; j > 0; --j) {
            acc.extend(bin_box[j]);
            cnt += bin_n[j];
            right_cost[j] = cnt ? acc.surface_area() * float(blocks(cnt)) : infinity<float>;
        }
        acc = AABB<float>{};
        cnt = 0;
        bool improved = false;
        for (std::uint32_t j = 1; j < opt_.bins; ++j) {
            acc.extend(bin_box[j - 1]);
            cnt += bin_n[j - 1];
            if (cnt == 0 || cnt == n) continue;
            const float c = opt_.traversal_cost +
                            opt_.intersection_cost * (acc.surface_area() * float(blocks(cnt)) + right_cost[j]) * inv_area;
            if (c < best.cost) {
                best = SahSplit{a, j, c, acc, {}};
                improved = true;
            }
        }
        if (improved)
            for (std::uint32_t j = best.bin; j < opt_.bins; ++j) best.right.extend(bin_box[j]);
    }

    std::span<const AABB<float>> boxes_;
    std::span<const Vec3f> centres_;
    const BvhBuildOptions& opt_;
    BinaryBvh& out_;
    std::atomic<int> tokens_;  // threads that may still be started
};

}  // namespace detail

/// Builds the binned SAH tree over the primitives whose box is not empty and finite
/// (others are left out: they can never be hit).
inline BinaryBvh build_binary_bvh(std::span<const AABB<float>> boxes, const BvhBuildOptions& opt = {}) {
    opt.check();
    BinaryBvh out;
    AABB<float> root;
    for (std::uint32_t i = 0; i < boxes.size(); ++i) {
        const AABB<float>& b = boxes[i];
        if (b.empty() || !all_finite(b.lo) || !all_finite(b.hi)) continue;
        out.prims.push_back(i);
        root.extend(b);
    }
    if (out.prims.empty()) return out;
    out.nodes.resize(2 * out.prims.size() - 1);
    std::vector<Vec3f> centres(boxes.size());
    for (std::uint32_t p : out.prims) centres[p] = boxes[p].center();
    detail::BinnedSah(boxes, centres, opt, out).node(0, 0, std::uint32_t(out.prims.size()), root);
    return out;
}

}  // namespace glint
