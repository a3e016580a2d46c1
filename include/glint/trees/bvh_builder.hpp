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
// Spatial splits (optional; Stich, Friedrich, Dietrich, "Spatial splits in bounding volume
// hierarchies", HPG 2009): where the best object split's two boxes overlap by more than
// alpha times the root's area, the node's box is also binned by position, each reference
// chopped into the bins it spans and clipped exactly to them (clip_triangle: the triangle
// polygon against the bin's planes), and a plane that cuts references in two wins when its
// SAH cost is lower; a reference then sits on both sides, each piece bounded by its part of
// the primitive, references at most spatial_budget times the primitives. Slots: binary_bvh.hpp.
// Cheaper searches (BvhBuildOptions::top_spatial_splits): only at the top levels, where the
// overlap is also a large part of the node's own area, on the longest axis, and by boxes: a
// reference counted whole in its first and last bin, the sides' boxes cut at the plane, so
// the search costs what an object binning does; the split it chooses still clips exactly.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/trees/binary_bvh.hpp>
#include <glint/trees/sah_binning.hpp>

namespace glint {

namespace detail {

/// The recursive build (Wald 2007), with spatial splits (Stich et al. 2009) where the options
/// ask for them. One object per build, shared by its threads.
/// A node owns a range [b, cap) of the reference array: its references are [b, e), and
/// [e, cap) is room for the references its spatial splits add. A split gives each child the
/// room in proportion to its references (as Embree's spatial-split builder does) and moves
/// the right child's references to the start of its room; a subtree whose room is c
/// references has at most 2c - 1 nodes, so the right child's slot is s + 2 (its first
/// reference - b), fixed before either child is built. Each node reads and writes only its
/// own range and slots, so the tree does not depend on the thread count. Without spatial
/// splits the room is the references (cap = e) and this is the object-split build alone.
template <PrimitiveClipper Clip>
class BinnedSah {
public:
    BinnedSah(std::vector<BvhRef>& refs, const BvhBuildOptions& opt, const Clip& clip, float root_area, std::uint32_t root_refs,
              BinaryBvh& out)
        : refs_(refs), scratch_(refs.size()), opt_(opt), clip_(clip), out_(out), tokens_(int(opt.thread_count()) - 1),
          spatial_(opt.spatial_splits),
          min_overlap_(opt.spatial_alpha * root_area),
          min_refs_(opt.spatial_levels ? std::max(2u, root_refs >> std::min(opt.spatial_levels, 31u)) : 0u), cost_(opt) {}

    /// The box of some references and the box of their centres.
    struct Bounds {
        AABB<float> box, cbox;
    };

    /// Builds the subtree at `slot` over refs[b, e) (room up to cap), whose bounds are `in`.
    void node(std::uint32_t slot, std::uint32_t b, std::uint32_t e, std::uint32_t cap, const Bounds& in,
              bool spatial = true) {
        const AABB<float>& box = in.box;
        BinaryBvhNode& nd = out_.nodes[slot];
        nd.box = box;
        nd.begin = b;
        nd.count = e - b;
        const std::uint32_t n = e - b;
        if (n < min_refs_) cap = e;  // no spatial split below: its children need no room
        // Every split costs at least C_T: where a leaf costs no more, it is a leaf unsearched.
        if (n == 1 || (n <= opt_.max_leaf && opt_.traversal_cost >= opt_.intersection_cost * float(blocks(n)))) return;
        const Vec3f k = scales(in.cbox);
        const BinMap map(in.cbox, k, opt_.bins);
        const float inv_area = 1.0f / std::max(box.surface_area(), std::numeric_limits<float>::min());
        const SahSplit s = find_split(b, e, map, k, inv_area);
        SahSplit sp;  // Stich et al. §4: spatial splits only where the object split's boxes overlap
        if (spatial && spatial_ && cap > e && n >= min_refs_ &&
            (s.axis < 0 || overlap_area(s.left, s.right) > std::max(min_overlap_, opt_.spatial_node_overlap * box.surface_area())))
            sp = find_spatial(b, e, cap - e, box, inv_area);
        if (n <= opt_.max_leaf && !(std::min(s.cost, sp.cost) < opt_.intersection_cost * float(blocks(n)))) return;
        if (sp.cost < s.cost) {
            // A side came out empty: boxes may have been clipped closer, so their centres again.
            if (!split_spatial(slot, b, e, cap, box, sp)) node(slot, b, e, cap, {box, bounds(b, e).cbox}, false);
            return;
        }
        if (s.axis >= 0) {
            Bounds l{s.left, {}}, r{s.right, {}};
            const std::uint32_t m = partition_by_bin(refs_.data(), scratch_.data(), b, e, map, s.axis, s.bin, l.cbox, r.cbox);
            return children(slot, b, m, e, cap, l, r);
        }
        const std::uint32_t m = b + n / 2;  // every centre is the same point: any halving is as good
        children(slot, b, m, e, cap, bounds(b, m), bounds(m, e));
    }

private:
    Bounds bounds(std::uint32_t b, std::uint32_t e) const {
        Bounds o;
        for (std::uint32_t i = b; i < e; ++i) {
            o.box.extend(refs_[i].box);
            o.cbox.extend(refs_[i].box.center());
        }
        return o;
    }
    std::uint32_t blocks(std::uint32_t n) const { return cost_.blocks(n); }
    static float overlap_area(const AABB<float>& a, const AABB<float>& b) {
        AABB<float> o;
        o.lo = glm::max(a.lo, b.lo);
        o.hi = glm::min(a.hi, b.hi);
        return o.surface_area();  // 0 when they do not overlap
    }
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

    /// The children of a node whose references are split into [b, m) and [m, e) (e <= cap):
    /// the room [e, cap) is shared in proportion to the references, the right child's
    /// references move to the start of its room, and its slot follows from the left room.
    void children(std::uint32_t slot, std::uint32_t b, std::uint32_t m, std::uint32_t e, std::uint32_t cap,
                  const Bounds& lb, const Bounds& rb) {
        const auto room_l = std::uint32_t(std::uint64_t(cap - e) * (m - b) / (e - b));
        if (room_l) std::move_backward(refs_.begin() + m, refs_.begin() + e, refs_.begin() + e + room_l);
        const std::uint32_t mid = m + room_l;  // the left room's end, the right child's first reference
        const std::uint32_t right = slot + 2 * (mid - b);
        out_.nodes[slot].right = right;
        recurse({slot + 1, b, m, mid}, lb, {right, mid, e + room_l, cap}, rb);
    }

    struct Range {
        std::uint32_t slot, b, e, cap;
    };
    /// Runs the two children; a large subtree's through the host's executor if given, else
    /// the left on a thread of its own if one is free (the tree does not depend on which
    /// runs where). A thread, and the waiting parent until the join, give the token back
    /// once done, so that the side still at work can split off again (uneven splits).
    void recurse(const Range& l, const Bounds& lb, const Range& r, const Bounds& rb) {
        constexpr std::uint32_t parallel_min = 4096;
        const bool large = (l.e - l.b) + (r.e - r.b) >= parallel_min;
        if (large && opt_.executor)  // the host's threads run both (BvhBuildOptions::executor)
            return opt_.executor(2, [&](int i) { i == 0 ? node(l.slot, l.b, l.e, l.cap, lb) : node(r.slot, r.b, r.e, r.cap, rb); });
        if (large && tokens_.fetch_sub(1) > 0) {
            std::thread left([&] {
                node(l.slot, l.b, l.e, l.cap, lb);
                tokens_.fetch_add(1);
            });
            node(r.slot, r.b, r.e, r.cap, rb);
            tokens_.fetch_add(1);  // this thread waits: another may run meanwhile
            left.join();
            tokens_.fetch_sub(1);
            return;
        }
        if (large) tokens_.fetch_add(1);
        node(l.slot, l.b, l.e, l.cap, lb);
        node(r.slot, r.b, r.e, r.cap, rb);
    }

    /// Bins every reference of the range on the three axes in one pass (sah_binning.hpp),
    /// then sweeps each axis for its cheapest boundary (Wald 2007).
    SahSplit find_split(std::uint32_t b, std::uint32_t e, const BinMap& map, const Vec3f& k, float inv_area) const {
        const SahBins bins(refs_.data(), b, e, map, opt_.bins, avx2_);
        SahSplit best;
        AABB<float> box[SahBins::max_bins];
        std::uint32_t count[SahBins::max_bins], bin[SahBins::max_bins];
        for (int a = 0; a < 3; ++a)
            if (k[a] != 0.0f) sweep_bins(cost_, a, box, count, bin, bins.axis(a, box, count, bin), inv_area, best);
        return best;
    }
    /// The cheapest boundary on axis a, if cheaper than `best`: suffix costs right to left,
    /// then prefixes left to right. A reference counts on the left of boundary j if its first
    /// bin (enter) is below j, on the right if its last bin (leave) is j or above: an object
    /// split passes the same counts twice; a spatial split may add at most `room` references.
    /// A side's box is the union of its bins' boxes (lbox from the left, rbox from the right)
    /// cut at the boundary's plane: pieces clipped to their bins are already within it, whole
    /// boxes counted in their first and last bins only (box chop) are chopped by the cut.
    void sweep(int a, const AABB<float>& node, const AABB<float>* lbox, const AABB<float>* rbox,
               const std::uint32_t* enter, const std::uint32_t* leave, std::uint32_t n, std::uint32_t room,
               float inv_area, SahSplit& best) const {
        float right_cost[64];
        std::uint32_t right_n[64];
        AABB<float> right_box[64];
        AABB<float> acc;
        std::uint32_t cnt = 0;
        for (std::uint32_t j = opt_.bins - 1; j > 0; --j) {
            acc.extend(rbox[j]);
            cnt += leave[j];
            right_n[j] = cnt;
            right_box[j] = acc;
            right_box[j].lo[a] = std::min(acc.hi[a], std::max(acc.lo[a], plane(node, a, j)));
            right_cost[j] = cnt ? right_box[j].surface_area() * float(blocks(cnt)) : infinity<float>;
        }
        acc = AABB<float>{};
        cnt = 0;
        for (std::uint32_t j = 1; j < opt_.bins; ++j) {
            acc.extend(lbox[j - 1]);
            cnt += enter[j - 1];
            if (cnt == 0 || right_n[j] == 0 || cnt + right_n[j] > n + room) continue;
            AABB<float> l = acc;
            l.hi[a] = std::max(acc.lo[a], std::min(acc.hi[a], plane(node, a, j)));
            const float c = opt_.traversal_cost +
                            opt_.intersection_cost * (l.surface_area() * float(blocks(cnt)) + right_cost[j]) * inv_area;
            if (c < best.cost) best = SahSplit{a, j, c, l, right_box[j], cnt, right_n[j]};
        }
    }

    /// Spatial bin boundary j of the node box on axis a (sah_binning.hpp's spatial_plane).
    float plane(const AABB<float>& box, int a, std::uint32_t j) const { return spatial_plane(box, a, j, opt_.bins); }

    /// Spatial split search (Stich et al. 2009 §3): bins of equal width over the node box;
    /// each reference is chopped into the bins it spans, each piece clipped to its bin, and
    /// counted as entering its first bin and leaving its last. With spatial_box_chop a
    /// reference's whole box is counted in its first and last bins only and the sweep cuts the
    /// sides' boxes at the plane (the box's chop, no clipping: one pass as cheap as object
    /// binning); with spatial_one_axis only the node's longest axis is binned.
    SahSplit find_spatial(std::uint32_t b, std::uint32_t e, std::uint32_t room, const AABB<float>& box,
                          float inv_area) const {
        SahSplit best;
        const int longest = box.longest_axis();
        for (int a = 0; a < 3; ++a) {
            if (!(box.hi[a] > box.lo[a]) || (opt_.spatial_one_axis && a != longest)) continue;
            AABB<float> bin_box[64], rbox[64];
            std::uint32_t enter[64] = {}, leave[64] = {};
            const SpatialBins sb(box, a, opt_.bins);
            for (std::uint32_t i = b; i < e; ++i) {
                const BvhRef& r = refs_[i];
                const std::uint32_t last = sb.to(r.box.hi[a]);
                const std::uint32_t first = std::min(last, sb.from(r.box.lo[a]));  // min: flat on a plane
                ++enter[first];
                ++leave[last];
                if (opt_.spatial_box_chop) {
                    bin_box[first].extend(r.box);
                    rbox[last].extend(r.box);
                    continue;
                }
                if (first == last) {
                    bin_box[first].extend(r.box);
                    continue;
                }
                for (std::uint32_t j = first; j <= last; ++j) {
                    AABB<float> region = r.box;
                    if (j > first) region.lo[a] = sb.pl[j];
                    if (j < last) region.hi[a] = sb.pl[j + 1];
                    bin_box[j].extend(clip_(r.prim, a, region));
                }
            }
            sweep(a, box, bin_box, opt_.spatial_box_chop ? rbox : bin_box, enter, leave, e - b, room, inv_area, best);
        }
        return best;
    }

    /// Sides of one straddling reference r at plane pos of axis a: both pieces (true: the
    /// right one was written at refs_[spare]), or the whole reference on one side where Stich
    /// et al.'s reference unsplitting (§4) finds that cheaper or no room is left (spare == cap).
    bool straddle(BvhRef& r, int a, float pos, const SahSplit& s, std::uint32_t spare, std::uint32_t cap) {
        AABB<float> lp = r.box, rp = r.box;
        lp.hi[a] = pos;
        rp.lo[a] = pos;
        lp = clip_(r.prim, a, lp);
        rp = clip_(r.prim, a, rp);
        if (lp.empty() || rp.empty()) {  // the primitive's part lies on one side only
            r.left = !lp.empty() || rp.empty();
            if (!(lp.empty() && rp.empty())) r.box = lp.empty() ? rp : lp;
            return false;
        }
        AABB<float> wl = s.left, wr = s.right;
        wl.extend(r.box);
        wr.extend(r.box);
        const float nl = float(s.n_left), nr = float(s.n_right), al = s.left.surface_area(), ar = s.right.surface_area();
        const float both = al * nl + ar * nr, to_left = wl.surface_area() * nl + ar * (nr - 1),
                    to_right = al * (nl - 1) + wr.surface_area() * nr;
        if (spare == cap || to_left < both || to_right < both) {
            r.left = to_left <= to_right;
            return false;
        }
        r.box = lp;
        r.left = 1;
        refs_[spare] = BvhRef{rp, r.prim, 0};
        return true;
    }

    /// Makes the spatial split s: references left of, right of and across the plane, the
    /// children's boxes from the pieces themselves; false (nothing but boxes clipped closer
    /// changed) when one side came out empty.
    bool split_spatial(std::uint32_t slot, std::uint32_t b, std::uint32_t e, std::uint32_t cap, const AABB<float>& box,
                       const SahSplit& s) {
        const int a = s.axis;
        const float pos = plane(box, a, s.bin);
        std::uint32_t end = e;
        for (std::uint32_t i = b; i < e; ++i) {
            BvhRef& r = refs_[i];
            r.left = r.box.hi[a] <= pos;
            if (!r.left && r.box.lo[a] < pos && straddle(r, a, pos, s, end, cap)) ++end;
        }
        const auto mid = std::partition(refs_.begin() + b, refs_.begin() + end, [](const BvhRef& r) { return r.left != 0; });
        const auto m = std::uint32_t(mid - refs_.begin());
        if (m == b || m == end) return false;  // only when nothing was appended
        children(slot, b, m, end, cap, bounds(b, m), bounds(m, end));
        return true;
    }

    std::vector<BvhRef>& refs_;
    std::vector<BvhRef> scratch_;  // the partition's, each node's range its own
    const BvhBuildOptions& opt_;
    const Clip& clip_;
    BinaryBvh& out_;
    std::atomic<int> tokens_;  // threads that may still be started
    const bool spatial_;
    const float min_overlap_;
    const std::uint32_t min_refs_;  // spatial splits only at nodes of at least this many references
    const SahCosts cost_;
    const bool avx2_ = best_isa() >= Isa::avx2;  // bin with AVX2 (sah_binning.hpp)
};

/// The leaves' references, in tree order, become `prims`; every node's range is renumbered
/// to match (the room spatial splits left unused disappears).
inline void bvh_compact(BinaryBvh& out, const std::vector<BvhRef>& refs, std::uint32_t slot) {
    BinaryBvhNode& nd = out.nodes[slot];
    const auto begin = std::uint32_t(out.prims.size());
    if (nd.leaf()) {
        for (std::uint32_t i = nd.begin; i < nd.begin + nd.count; ++i) out.prims.push_back(refs[i].prim);
    } else {
        bvh_compact(out, refs, slot + 1);
        bvh_compact(out, refs, nd.right);
    }
    nd.begin = begin;
    nd.count = std::uint32_t(out.prims.size()) - begin;
}

}  // namespace detail

/// Builds the binned SAH tree over primitives 0 ... n - 1 whose box box_of(i) is not empty
/// and finite (others are left out: they can never be hit), without an array of boxes. With
/// opt.spatial_splits, `clip` chops primitives at split planes (clip_triangle for triangles;
/// NoClipper chops their boxes); a primitive may then be in several leaves (prims holds it
/// once per leaf), at most opt.spatial_budget times the primitives in all.
template <class BoxOf, PrimitiveClipper Clip = NoClipper>
    requires std::convertible_to<std::invoke_result_t<const BoxOf&, std::uint32_t>, AABB<float>>
BinaryBvh build_binary_bvh(std::size_t n, const BoxOf& box_of, const BvhBuildOptions& opt = {}, const Clip& clip = {}) {
    opt.check();
    // References for m primitives with the room spatial splits may add.
    const auto with_room = [&](std::size_t m) {
        return opt.spatial_splits ? std::max(m, std::size_t(double(m) * double(opt.spatial_budget))) : m;
    };
    std::vector<detail::BvhRef> refs;
    refs.reserve(with_room(n));  // once: the references kept are at most n
    typename detail::BinnedSah<Clip>::Bounds root;
    for (std::uint32_t i = 0; i < n; ++i) {
        const AABB<float> b = box_of(i);
        if (b.empty() || !all_finite(b.lo) || !all_finite(b.hi)) continue;
        refs.push_back({b, i, 0});
        root.box.extend(b);
        root.cbox.extend(b.center());
    }
    BinaryBvh out;
    if (refs.empty()) return out;
    const std::size_t kept = refs.size();
    const std::size_t cap = with_room(kept);
    if (cap >= (std::size_t(1) << 31))
        throw Error("build_binary_bvh: " + std::to_string(cap) + " references, at most 2^31 - 1");
    refs.resize(cap);
    out.nodes.resize(2 * cap - 1);
    detail::BinnedSah<Clip>(refs, opt, clip, root.box.surface_area(), std::uint32_t(kept), out)
        .node(0, 0, std::uint32_t(kept), std::uint32_t(cap), root);
    if (cap == kept) {  // no room was left: every node's range is already its place in tree order
        out.prims.resize(kept);
        for (std::size_t i = 0; i < kept; ++i) out.prims[i] = refs[i].prim;
        return out;
    }
    out.prims.reserve(cap);
    detail::bvh_compact(out, refs, 0);
    return out;
}

/// build_binary_bvh over boxes[i] for every i.
template <PrimitiveClipper Clip = NoClipper>
BinaryBvh build_binary_bvh(std::span<const AABB<float>> boxes, const BvhBuildOptions& opt = {}, const Clip& clip = {}) {
    return build_binary_bvh(boxes.size(), [&](std::uint32_t i) { return boxes[i]; }, opt, clip);
}

}  // namespace glint
