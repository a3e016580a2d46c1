// glint/trees/wide_packet.hpp: packet traversal of the wide BVH (wide_bvh.hpp): up to 16
// rays share each node visit (Wald, Slusallek, Benthin, Wagner 2001's ray packets: coherent
// rays traced together, a node entered when any ray of the packet enters it), after an
// interval test of the whole packet (Boulos, Wald, Shirley, Parker 2006).
//
// The rays sit in the lanes of vectors; a node's children are tested one at a time
// against all lanes (each child's 6 planes broadcast), which gives each child directly the
// lanes that enter it: the child goes on the stack with that lane mask and the lanes' entry
// distances, and is visited with only those lanes. Children are visited nearest first by the
// entry distance of their lowest lane. A popped entry keeps only the lanes whose entry
// distance is still within their interval (closest hit) or which have not found a hit yet
// (any hit). Leaves go to the caller's leaf callable `leaf(lanes, first, count, tmax)`
// with the lanes that enter them (trees/packet_leaf.hpp tests them all at once; closest hit
// lowers the lanes' tmax).
//
// Each lane computes the very floats of the single-ray box test (wide_box_test.hpp: Ize
// 2013's enlarged exit distance), so a lane never misses a box its single ray would enter;
// a ray's hit is the nearest of the triangles it tests, whatever the order, so packet and
// single ray give the same hit (up to exact ties between two triangles at one distance).
//
// The packet needs one near / far plane choice per axis: every ray's direction has the same
// signs, and every interval starts at 0 or later (the unsigned box test). packet_shape()
// says whether rays qualify, for_sign_groups() splits a packet's rays into groups that do;
// a caller traces the rest as single rays.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include <glint/core/isa.hpp>
#include <glint/core/ray.hpp>
#include <glint/trees/packet_rays.hpp>
#include <glint/trees/wide_box_test.hpp>
#include <glint/trees/wide_node.hpp>

#if GLINT_X86
#include <immintrin.h>
#endif

namespace glint {

namespace detail {

/// Bounds of the distances (plane - o) * inv over the packet's intervals of o and inv, as
/// floats (rounded subtraction and multiplication are monotone in each operand, so the
/// extremes are at the corners): the smallest (Max = false) or the largest.
template <bool Max>
[[gnu::always_inline]] inline float packet_corner(float plane, float o0, float o1, float i0, float i1) {
    const float d0 = plane - o1, d1 = plane - o0;
    const float a = d0 * i0, b = d0 * i1, c = d1 * i0, d = d1 * i1;
    return Max ? std::max(std::max(a, b), std::max(c, d)) : std::min(std::min(a, b), std::min(c, d));
}

/// The children of n that some ray of the packet may enter (Boulos 2006's interval
/// arithmetic, on the packet's intervals of origin and reciprocal direction): a
/// superset of those the lane tests accept, for tmin >= tmin_lo and tmax <= tmax_hi.
template <int N>
[[gnu::always_inline]] inline unsigned packet_candidates(const PacketBounds& p, const WideBvhNode<N>& n, float tmax_hi) {
    unsigned mask = 0;
    for (int i = 0; i < N; ++i) {
        float t0 = p.tmin_lo, t1 = tmax_hi;
        for (int a = 0; a < 3; ++a) {
            t0 = std::max(t0, packet_corner<false>(n.bounds[p.near[a]][i], p.omin[a], p.omax[a], p.imin[a], p.imax[a]));
            t1 = std::min(t1, packet_corner<true>(n.bounds[p.far[a]][i], p.omin[a], p.omax[a], p.imin[a], p.imax[a]));
        }
        mask |= unsigned(t0 <= t1 * wide_exit_scale) << i;
    }
    return mask;
}

/// One child's box against every lane: the lanes that enter it within (tmin, tmax[k]), their
/// entry distances in tn; the single-ray test's operations lane by lane (portable, SSE2).
template <Isa I>
struct PacketBoxTest {
    PacketRays p;

    /// The rays `s.lanes` of r, a coherent packet (packet_shape).
    [[gnu::always_inline]] PacketBoxTest(const PacketRaySoa& r, const PacketShape& s) : p(r, s) {}
    template <int N>
    [[gnu::always_inline]] unsigned test(const WideBvhNode<N>& n, int i, const float* tmax, float* tn) const {
        unsigned mask = 0;
        for (int k = 0; k < packet_lanes; ++k) {
            float t0 = p.tmin[k], t1 = tmax[k];
            for (int a = 0; a < 3; ++a) {
                const float tl = (n.bounds[p.near[a]][i] - p.o[a][k]) * p.inv[a][k];
                const float th = (n.bounds[p.far[a]][i] - p.o[a][k]) * p.inv[a][k];
                t0 = tl > t0 ? tl : t0;
                t1 = th < t1 ? th : t1;
            }
            tn[k] = t0;
            mask |= unsigned(t0 <= t1 * wide_exit_scale) << k;
        }
        return mask;
    }
    /// The children some ray may enter (packet_candidates; all where the packet is unbounded).
    template <int N>
    [[gnu::always_inline]] unsigned candidates(const WideBvhNode<N>& n, float tmax_hi) const {
        return p.bounded ? packet_candidates(p, n, tmax_hi) : (1u << N) - 1u;
    }
    /// The lanes whose entry distance t[k] is still within their interval.
    [[gnu::always_inline]] unsigned within(const float* t, const float* tmax) const {
        unsigned mask = 0;
        for (int k = 0; k < packet_lanes; ++k) mask |= unsigned(t[k] <= tmax[k] * wide_exit_scale) << k;
        return mask;
    }
};

#if GLINT_X86
/// The same with AVX2: one child's planes broadcast against the lanes, 8 at a time (all 16
/// in one AVX-512 vector where the flags give AVX-512).
template <>
struct PacketBoxTest<Isa::avx2> {
    static constexpr int H = packet_lanes / 8;  // vectors of 8 lanes
    alignas(64) float o[3][packet_lanes], inv[3][packet_lanes], tmin[packet_lanes];
    int near[3], far[3];
    PacketBounds p;

    /// The rays `s.lanes` of r, a coherent packet (packet_shape): PacketRays' floats,
    /// computed in vectors.
    GLINT_KERNEL_AVX2 PacketBoxTest(const PacketRaySoa& r, const PacketShape& s) {
        p.set_planes(r, std::countr_zero(s.lanes));
        const __m256 inf = _mm256_set1_ps(infinity<float>), ninf = _mm256_set1_ps(-infinity<float>);
        const __m256 one = _mm256_set1_ps(1.0f), bit = _mm256_castsi256_ps(_mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128));
        __m256 lo[3], hi[3], ilo[3], ihi[3], tlo = inf;
        for (int a = 0; a < 3; ++a) lo[a] = ilo[a] = inf, hi[a] = ihi[a] = ninf;
        for (int h = 0; h < H; ++h) {
            const __m256 lanes = _mm256_castsi256_ps(_mm256_set1_epi32(int((s.lanes >> (8 * h)) & 0xffu)));
            const __m256 in = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                _mm256_castps_si256(_mm256_and_ps(lanes, bit)), _mm256_castps_si256(bit)));
            const __m256 t = _mm256_blendv_ps(inf, _mm256_loadu_ps(r.tmin + 8 * h), in);
            _mm256_store_ps(tmin + 8 * h, t);
            tlo = _mm256_min_ps(tlo, t);
            for (int a = 0; a < 3; ++a) {
                const __m256 oa = _mm256_loadu_ps(r.o[a] + 8 * h);
                const __m256 ia = _mm256_div_ps(one, _mm256_loadu_ps(r.d[a] + 8 * h));
                _mm256_store_ps(o[a] + 8 * h, _mm256_and_ps(oa, in));  // 0 outside the packet
                _mm256_store_ps(inv[a] + 8 * h, _mm256_blendv_ps(one, ia, in));
                lo[a] = _mm256_min_ps(lo[a], _mm256_blendv_ps(inf, oa, in));
                hi[a] = _mm256_max_ps(hi[a], _mm256_blendv_ps(ninf, oa, in));
                ilo[a] = _mm256_min_ps(ilo[a], _mm256_blendv_ps(inf, ia, in));
                ihi[a] = _mm256_max_ps(ihi[a], _mm256_blendv_ps(ninf, ia, in));
            }
        }
        p.tmin_lo = extreme<false>(tlo);
        for (int a = 0; a < 3; ++a) {
            p.omin[a] = extreme<false>(lo[a]), p.omax[a] = extreme<true>(hi[a]);
            p.imin[a] = extreme<false>(ilo[a]), p.imax[a] = extreme<true>(ihi[a]);
            near[a] = p.near[a], far[a] = p.far[a];
        }
        p.set_bounded();
    }
    /// The smallest (Max = false) or largest of v's 8 lanes.
    template <bool Max>
    GLINT_KERNEL_AVX2 static float extreme(__m256 v) {
        const auto f = [](__m128 x, __m128 y) __attribute__((always_inline)) {
            return Max ? _mm_max_ps(x, y) : _mm_min_ps(x, y);
        };
        __m128 m = f(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
        m = f(m, _mm_movehl_ps(m, m));
        return _mm_cvtss_f32(f(m, _mm_shuffle_ps(m, m, 1)));
    }
    template <int N>
    GLINT_KERNEL_AVX2 unsigned test(const WideBvhNode<N>& n, int i, const float* tmax, float* tn) const {
#if defined(__AVX512F__)
        if constexpr (H == 2) {
            __m512 t0 = _mm512_load_ps(tmin), t1 = _mm512_loadu_ps(tmax);
            for (int a = 0; a < 3; ++a) {
                const __m512 o16 = _mm512_load_ps(o[a]), inv16 = _mm512_load_ps(inv[a]);
                const __m512 bn = _mm512_set1_ps(n.bounds[near[a]][i]), bf = _mm512_set1_ps(n.bounds[far[a]][i]);
                // maskz: GCC 12's _mm512_max_ps / min_ps warn of their undefined pass-through
                t0 = _mm512_maskz_max_ps(0xffff, _mm512_mul_ps(_mm512_sub_ps(bn, o16), inv16), t0);
                t1 = _mm512_maskz_min_ps(0xffff, _mm512_mul_ps(_mm512_sub_ps(bf, o16), inv16), t1);
            }
            _mm512_storeu_ps(tn, t0);
            t1 = _mm512_mul_ps(t1, _mm512_set1_ps(wide_exit_scale));
            return unsigned(_mm512_cmp_ps_mask(t0, t1, _CMP_LE_OQ));
        }
#endif
        unsigned mask = 0;
        for (int h = 0; h < H; ++h) {
            __m256 t0 = _mm256_load_ps(tmin + 8 * h), t1 = _mm256_load_ps(tmax + 8 * h);
            for (int a = 0; a < 3; ++a) {
                const __m256 bn = _mm256_broadcast_ss(&n.bounds[near[a]][i]);
                const __m256 bf = _mm256_broadcast_ss(&n.bounds[far[a]][i]);
                const __m256 oh = _mm256_load_ps(o[a] + 8 * h), ih = _mm256_load_ps(inv[a] + 8 * h);
                t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(bn, oh), ih), t0);
                t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(bf, oh), ih), t1);
            }
            _mm256_store_ps(tn + 8 * h, t0);
            t1 = _mm256_mul_ps(t1, _mm256_set1_ps(wide_exit_scale));
            mask |= unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ))) << (8 * h);
        }
        return mask;
    }
    /// packet_candidates() with the 8 children in the lanes (the same floats).
    GLINT_KERNEL_AVX2 unsigned candidates(const WideBvhNode<8>& n, float tmax_hi) const {
        if (!p.bounded) return 0xffu;
        __m256 t0 = _mm256_set1_ps(p.tmin_lo), t1 = _mm256_set1_ps(tmax_hi);
        for (int a = 0; a < 3; ++a) {
            const __m256 o0 = _mm256_set1_ps(p.omin[a]), o1 = _mm256_set1_ps(p.omax[a]);
            const __m256 i0 = _mm256_set1_ps(p.imin[a]), i1 = _mm256_set1_ps(p.imax[a]);
            const __m256 ln = _mm256_load_ps(n.bounds[near[a]]), lf = _mm256_load_ps(n.bounds[far[a]]);
            const __m256 n0 = _mm256_sub_ps(ln, o1), n1 = _mm256_sub_ps(ln, o0);
            const __m256 f0 = _mm256_sub_ps(lf, o1), f1 = _mm256_sub_ps(lf, o0);
            const __m256 tl = _mm256_min_ps(_mm256_min_ps(_mm256_mul_ps(n0, i0), _mm256_mul_ps(n0, i1)),
                                            _mm256_min_ps(_mm256_mul_ps(n1, i0), _mm256_mul_ps(n1, i1)));
            const __m256 th = _mm256_max_ps(_mm256_max_ps(_mm256_mul_ps(f0, i0), _mm256_mul_ps(f0, i1)),
                                            _mm256_max_ps(_mm256_mul_ps(f1, i0), _mm256_mul_ps(f1, i1)));
            t0 = _mm256_max_ps(t0, tl);
            t1 = _mm256_min_ps(t1, th);
        }
        t1 = _mm256_mul_ps(t1, _mm256_set1_ps(wide_exit_scale));
        return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ)));
    }
    template <int N>
    unsigned candidates(const WideBvhNode<N>& n, float tmax_hi) const {
        return p.bounded ? packet_candidates(p, n, tmax_hi) : (1u << N) - 1u;
    }
    GLINT_KERNEL_AVX2 unsigned within(const float* t, const float* tmax) const {
        unsigned mask = 0;
        for (int h = 0; h < H; ++h) {
            const __m256 t1 = _mm256_mul_ps(_mm256_load_ps(tmax + 8 * h), _mm256_set1_ps(wide_exit_scale));
            mask |= unsigned(_mm256_movemask_ps(_mm256_cmp_ps(_mm256_load_ps(t + 8 * h), t1, _CMP_LE_OQ))) << (8 * h);
        }
        return mask;
    }
};
#endif

/// A node as the packet test reads it: float nodes as they are, quantized ones decoded.
template <int N>
[[gnu::always_inline]] inline const WideBvhNode<N>& packet_node(const WideBvhNode<N>& n, WideBvhNode<N>&) {
    return n;
}
template <int N>
[[gnu::always_inline]] inline const WideBvhNode<N>& packet_node(const WideBvhQNode<N>& q, WideBvhNode<N>& buf) {
    buf = wide_decode(q);
    return buf;
}

/// The largest of the packet's tmax.
[[gnu::always_inline]] inline float packet_max(const float* tmax) {
    float m = tmax[0];
    for (int k = 1; k < packet_lanes; ++k) m = std::max(m, tmax[k]);
    return m;
}

/// A child on the packet's stack: its reference, lanes, and their entry distances.
struct alignas(32) PacketEntry {
    float t[packet_lanes];
    std::uint32_t ref;
    unsigned lanes;
    float key;  // the entry distance of the lowest lane: the visiting order
};

/// Pushes the children of node n that some lane of `lanes` enters onto stack[sp...], the
/// nearest last where Sort (closest hit; any hit takes them in the node's order, as the
/// single ray's traverse_any); returns how many.
template <int N, bool Sort, class Test>
[[gnu::always_inline]] inline int packet_children(const WideBvhNode<N>& n, const Test& box, unsigned lanes,
                                                  const float* tmax, float tmax_hi, PacketEntry* stack, int sp) {
    int c = 0;
    for (unsigned cand = box.candidates(n, tmax_hi); cand; cand &= cand - 1) {
        const int i = std::countr_zero(cand);
        if (n.child[i] == wide_empty_ref) continue;
        PacketEntry& e = stack[sp + c];
        e.lanes = box.test(n, i, tmax, e.t) & lanes;
        if (e.lanes == 0) continue;
        e.ref = n.child[i];
        e.key = e.t[std::countr_zero(e.lanes)];
        if constexpr (Sort)
            for (int j = sp + c; j > sp && stack[j - 1].key < stack[j].key; --j) std::swap(stack[j - 1], stack[j]);
        ++c;
    }
    return c;
}

/// Closest (Any = false) or any hit of the packet's rays (lanes `lanes`, a coherent
/// PacketShape's; their intervals end at tmax0[k]) through nodes (root at 0):
/// `leaf(lanes, first, count, tmax)` tests the rays of `lanes` against a leaf and returns
/// those that found a hit (closest hit: a hit nearer than tmax[k], which it lowers to it).
/// `node_hook(lanes)` is called at every inner node with the lanes that test its children.
/// `stack` holds the tree's stack bound (WideBvh::max_stack entries; one per stream, not per
/// packet). Returns the lanes that found a hit.
template <bool Any, int N, Isa I, class Node, class Leaf, class Hook>
[[gnu::always_inline]] inline unsigned packet_traverse(const Node* nodes, const PacketBoxTest<I>& box,
                                                       const float* tmax0, unsigned lanes, Leaf& leaf, Hook& node_hook,
                                                       PacketEntry* stack) {
    alignas(32) float tmax[packet_lanes];
    for (int k = 0; k < packet_lanes; ++k) tmax[k] = (lanes >> k) & 1u ? tmax0[k] : -infinity<float>;
    float tmax_hi = packet_max(tmax);  // the largest tmax of the packet
    WideBvhNode<N> decoded;
    unsigned found = 0, cur = lanes;
    std::uint32_t ref = 0;
    int sp = 0;
    for (;;) {
        if (!wide_is_leaf(ref)) {
            node_hook(cur);
            const int c = packet_children<N, !Any>(packet_node(nodes[ref], decoded), box, cur, tmax, tmax_hi, stack, sp);
            if (c > 0) {  // the nearest child next, the others on the stack
                sp += c - 1;
                ref = stack[sp].ref;
                cur = stack[sp].lanes;
                continue;
            }
        } else {
            const unsigned hit = leaf(cur, wide_leaf_first(ref), wide_leaf_count(ref), tmax);
            found |= hit;
            if constexpr (Any) {
                lanes &= ~hit;
                if (lanes == 0) return found;
            } else if (hit) {
                tmax_hi = packet_max(tmax);
            }
        }
        do {
            if (sp == 0) return found;
            --sp;
            cur = stack[sp].lanes & lanes;
            if constexpr (!Any) cur &= box.within(stack[sp].t, tmax);
        } while (cur == 0);
        ref = stack[sp].ref;
    }
}

}  // namespace detail

}  // namespace glint
