// glint/trees/early_split.hpp: early split clipping of long, thin primitives before the binned
// SAH build (bvh_builder.hpp).
//
// Ernst and Greiner, "Early split clipping for bounding volume hierarchies" (IEEE RT 2007):
// a triangle whose box is much larger than the triangle (a sliver lying diagonally) makes every
// node above it large. Before the build, such a reference is cut at its box's longest axis'
// midpoint, each half's box clipped to the triangle's part in it (the PrimitiveClipper, as for
// spatial splits), and the halves are cut again while that pays. Here a cut is made when the two
// halves' boxes have together less than `ratio` times the box's surface area (references whose
// box is smaller than the mean are left whole: they would save little), largest saving of
// area first (the SAH's measure; Karras and Aila 2013 likewise spend a fixed split budget where
// the area gained is largest), until the references are `budget` times the primitives. A
// primitive may then sit in several leaves; the builder keeps it once per leaf.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <queue>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/trees/binary_bvh.hpp>
#include <glint/trees/sah_binning.hpp>

namespace glint::detail {

/// A reference's cut at its box's longest axis' midpoint: the halves' clipped boxes and the
/// surface area the cut saves (box minus both halves; <= 0 when the cut does not pay).
struct EarlyCut {
    AABB<float> left, right;
    float gain = 0.0f;
    std::uint32_t slot = 0;  ///< The reference's index in the array.
    bool operator<(const EarlyCut& o) const { return gain < o.gain; }  ///< Heap order: least gain first out last.
};

/// Cuts reference `r` (at `slot`) at its box's longest axis' midpoint; gain <= 0 when the halves'
/// boxes have together `ratio` times the box's area or more (then the cut is not made).
template <PrimitiveClipper Clip>
EarlyCut early_cut(const BvhRef& r, std::uint32_t slot, const Clip& clip, float ratio) {
    EarlyCut c;
    c.slot = slot;
    const Vec3f ext = r.box.hi - r.box.lo;
    const int axis = ext.x >= ext.y ? (ext.x >= ext.z ? 0 : 2) : (ext.y >= ext.z ? 1 : 2);
    const float mid = 0.5f * (r.box.lo[axis] + r.box.hi[axis]);
    if (!(mid > r.box.lo[axis] && mid < r.box.hi[axis])) return c;  // too thin to cut
    AABB<float> lo = r.box, hi = r.box;
    lo.hi[axis] = mid;
    hi.lo[axis] = mid;
    c.left = clip(r.prim, axis, lo);
    c.right = clip(r.prim, axis, hi);
    if (c.left.empty() || c.right.empty()) return c;
    const float area = r.box.surface_area(), halves = c.left.surface_area() + c.right.surface_area();
    if (halves < ratio * area) c.gain = area - halves;
    return c;
}

/// Early split clipping over `refs` (see the file comment): appends the pieces, references at
/// most `budget` times their count on entry. Returns the references added.
template <PrimitiveClipper Clip>
std::size_t early_split(std::vector<BvhRef>& refs, const Clip& clip, float ratio, float budget) {
    const std::size_t n = refs.size();
    const auto cap = std::size_t(double(n) * double(budget));
    if (cap <= n) return 0;
    double sum = 0;  // boxes below the mean area save little: not clipped at all
    for (const BvhRef& r : refs) sum += double(r.box.surface_area());
    const auto mean = float(sum / double(n));
    std::vector<EarlyCut> heap;
    for (std::size_t i = 0; i < n; ++i) {
        if (!(refs[i].box.surface_area() > mean)) continue;
        EarlyCut c = early_cut(refs[i], std::uint32_t(i), clip, ratio);
        if (c.gain > 0) heap.push_back(c);
    }
    std::priority_queue<EarlyCut> queue(std::less<EarlyCut>(), std::move(heap));
    refs.reserve(cap);
    while (refs.size() < cap && !queue.empty()) {
        const EarlyCut c = queue.top();
        queue.pop();
        const std::uint32_t prim = refs[c.slot].prim;
        refs[c.slot].box = c.left;
        refs.push_back({c.right, prim, 0});
        for (std::uint32_t s : {c.slot, std::uint32_t(refs.size() - 1)}) {
            EarlyCut next = early_cut(refs[s], s, clip, ratio);
            if (next.gain > 0) queue.push(next);
        }
    }
    return refs.size() - n;
}

}  // namespace glint::detail
