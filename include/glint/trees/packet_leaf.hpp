// glint/trees/packet_leaf.hpp: a leaf tested by a whole ray packet at once (wide_packet.hpp):
// one triangle record at a time, broadcast, against the packet's rays in the SIMD lanes
// (Wald, Slusallek, Benthin, Wagner 2001's packet triangle test), instead of each ray running
// the single-ray batch of 8 records.
//
// Each ray-triangle pair runs the very operations of the policy's test() (the same source,
// so the same floats and the same contractions as the single-ray batch), and a ray keeps the
// first record of the leaf, in record order, with the smallest t below its bound: what the
// single-ray leaf test keeps (the nearest lane of each batch, a later batch only when
// strictly nearer). Records that can never hit (the padding of a leaf's last batch, and
// degenerate triangles: zero edges) are skipped. Testing a record against the 16 rays costs
// two vectors of 8 (GCC keeps 256-bit vectors here), testing a batch of 8 records against one
// ray one, so a leaf with more than half as many live records as entering rays (per batch)
// is tested lane by lane with the single-ray batches instead (the threshold counted in
// instructions: docs/history/trees.md).
//
// It applies to policies whose per-ray data is the plain ray, without per-ray field choice,
// in the identity frame (Möller-Trumbore, the default of MeshBvh); others test each ray
// with its single-ray leaf test.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include <glint/intersection/frame.hpp>
#include <glint/intersection/intersector.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/trees/wide_packet.hpp>

namespace glint {

namespace detail {

/// Lanes of a packet leaf test (the rays of one packet).
inline constexpr int packet_leaf_lanes = packet_lanes;

/// Whether P's leaves can be tested by packet_leaf(): float records, plain ray data, no
/// per-ray choice of fields, identity frame.
template <class P>
inline constexpr bool packet_leaf_supported =
    std::is_same_v<typename P::scalar_type, float> && std::is_same_v<RayDataOf<P>, PlainRay<float>> &&
    std::is_same_v<glint::FrameOf<P>, IdentityFrame> &&
    !requires(const float* const (&in)[field_count<P>], const RayDataOf<P>& r, const float* (&out)[field_count<P>]) {
        P::select_fields(in, r, out);
    };

/// A packet's rays as the leaf test reads them (the rays as the query prepared them: their
/// plain ray data, PlainRay::from), and each ray's nearest hit so far: t (its bound: +inf for
/// any hit), u, v and the record index.
struct alignas(64) PacketLeafRays : PacketRaySoa {
    float t[packet_leaf_lanes], u[packet_leaf_lanes], v[packet_leaf_lanes];
    std::uint32_t id[packet_leaf_lanes];

    /// Each lane's hit bound t0(j) (for_lanes, as load()), u = v = id = 0.
    template <class Bound>
    [[gnu::always_inline]] void set_bounds(int n, Bound&& t0) {
        for_lanes(n, [&](int k, int j) __attribute__((always_inline)) { t[k] = t0(j), u[k] = v[k] = 0.0f, id[k] = 0; });
    }
};

/// The records of the batch starting at `first` that may hit: the policy's
/// P::live_records(block) where it has one (Möller-Trumbore: those with a non-zero edge),
/// else all.
template <class P>
[[gnu::always_inline]] inline unsigned packet_leaf_live(const RecordView<P>& view, std::uint32_t first) {
    if constexpr (requires { P::live_records(view.field(0, first)); }) return P::live_records(view.field(0, first));
    else return (1u << batch_width) - 1u;
}

/// Record `rec` (index `index`) against the lanes `lanes` of `p`: lanes it hits nearer than
/// their bound get the hit (closest hit; any hit: the bound stays +inf). Returns them. Two
/// loops over the lanes (the test, then the update), each of which GCC vectorizes.
template <class P>
[[gnu::always_inline]] inline unsigned packet_record(const P& rec, std::uint32_t index, unsigned lanes,
                                                     PacketLeafRays& p) {
    float ts[packet_leaf_lanes], us[packet_leaf_lanes], vs[packet_leaf_lanes];
    int oks[packet_leaf_lanes];
    for (int k = 0; k < packet_leaf_lanes; ++k) {
        PlainRay<float> r;
        r.o = Vec3<float>(p.o[0][k], p.o[1][k], p.o[2][k]);
        r.d = Vec3<float>(p.d[0][k], p.d[1][k], p.d[2][k]);
        r.tmin = p.tmin[k], r.tmax = p.tmax[k];
        float t, u, v;
        oks[k] = rec.test(r, t, u, v);
        ts[k] = t, us[k] = u, vs[k] = v;
    }
    unsigned found = 0;
    for (int k = 0; k < packet_leaf_lanes; ++k) {
        const bool ok = oks[k] & (ts[k] < p.t[k]) & ((lanes >> k) & 1u);
        p.t[k] = ok ? ts[k] : p.t[k];
        p.u[k] = ok ? us[k] : p.u[k];
        p.v[k] = ok ? vs[k] : p.v[k];
        p.id[k] = ok ? index : p.id[k];
        found |= unsigned(ok) << k;
    }
    return found;
}

/// Lane k of `p` against the batches of leaf (first, count) with the single-ray batch kernel,
/// as TriangleStore::test_batches runs them; true when it found a hit (closest hit: nearer
/// than p.t[k], which is lowered to it).
template <bool Any, class P>
[[gnu::always_inline]] inline bool packet_lane_leaf(const RecordView<P>& view, std::uint32_t first,
                                                    std::uint32_t count, int k, PacketLeafRays& p) {
    PlainRay<float> r;
    r.o = Vec3<float>(p.o[0][k], p.o[1][k], p.o[2][k]);
    r.d = Vec3<float>(p.d[0][k], p.d[1][k], p.d[2][k]);
    r.tmin = p.tmin[k], r.tmax = p.tmax[k];
    float ts[batch_width], us[batch_width], vs[batch_width];
    bool found = false;
    for (const std::uint32_t end = first + count; first < end; first += std::uint32_t(batch_width)) {
        batch_inlined<P>(view, first, batch_width, r, ts, us, vs);
        const int best = nearest_lane(ts, p.t[k]);
        if (best < 0) continue;
        if constexpr (Any) return true;
        p.t[k] = ts[best], p.u[k] = us[best], p.v[k] = vs[best];
        p.id[k] = first + std::uint32_t(best);
        found = true;
    }
    return found;
}

/// Leaf (first, count) of padded records (a TriangleLeaves leaf in the identity frame)
/// against the packet's lanes `lanes`: the lanes that found a hit in it (closest hit: nearer
/// than their bound p.t, which is lowered to it; any hit: every lane that hits, the test
/// stopping once all have). Record by record against all lanes where twice its live records
/// (a record against 16 lanes: two vectors of 8) are at most the lanes times its batches (a
/// batch against one lane: one vector), else lane by lane with the single-ray batches.
template <bool Any, class P>
[[gnu::always_inline]] inline unsigned packet_leaf(const RecordView<P>& view, std::uint32_t first, std::uint32_t count,
                                                   unsigned lanes, PacketLeafRays& p) {
    constexpr std::uint32_t W = std::uint32_t(batch_width);
    unsigned live[4] = {};  // leaves of up to 4 batches are tested record by record
    int records = 0;
    const std::uint32_t batches = (count + W - 1) / W;
    for (std::uint32_t b = 0; b < batches && b < 4; ++b) {
        live[b] = packet_leaf_live<P>(view, first + b * W);
        records += std::popcount(live[b]);
    }
    unsigned found = 0;
    if (batches > 4 || 2 * records > std::popcount(lanes) * int(batches)) {
        for (unsigned m = lanes; m; m &= m - 1)
            if (packet_lane_leaf<Any, P>(view, first, count, std::countr_zero(m), p)) found |= m & -m;
        return found;
    }
    for (std::uint32_t b = 0; b < batches; ++b) {
        for (unsigned l = live[b]; l; l &= l - 1) {
            const std::uint32_t i = first + b * W + std::uint32_t(std::countr_zero(l));
            found |= packet_record(load_record<P>(view, i), i, Any ? lanes & ~found : lanes, p);
            if (Any && found == lanes) return found;
        }
    }
    return found;
}

}  // namespace detail

}  // namespace glint
