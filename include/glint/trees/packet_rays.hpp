// glint/trees/packet_rays.hpp: the rays of a packet as the packet traversal
// (wide_packet.hpp) and the packet leaf test (packet_leaf.hpp) read them: up to 16 rays in
// structure-of-arrays form (PacketRaySoa, filled in loops the compiler vectorizes), whether
// they can be traced together (packet_shape: valid rays, one direction sign per axis, tmin
// >= 0; for_sign_groups: a packet's rays grouped by their signs where these differ), and what
// the packet's interval test needs (PacketBounds: the plane rows and the intervals of origins
// and reciprocal directions, Boulos, Wald, Shirley, Parker 2006).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/trees/wide_box_test.hpp>

namespace glint {

namespace detail {

/// Rays per packet (as Embree's 16-ray packets): one AVX-512 vector of floats in the lane
/// box test where the flags give AVX-512, two AVX2 vectors otherwise.
inline constexpr int packet_lanes = 16;
/// Fewer valid rays than this in a packet: single rays are cheaper.
inline constexpr int packet_min_rays = 2;
/// More direction sign classes than this among a packet's rays: they are incoherent (each
/// class a few rays from anywhere), single rays are cheaper (for_sign_groups).
inline constexpr int packet_max_groups = 4;

/// Calls f(k, j) for every lane k of a packet of n rays (n >= 1), j the ray it holds: k for
/// k < n, else 0 (so every lane holds a ray). A whole packet is a loop compilers vectorize.
template <class F>
[[gnu::always_inline]] inline void for_lanes(int n, F&& f) {
    if (n == packet_lanes)
        for (int k = 0; k < packet_lanes; ++k) f(k, k);
    else
        for (int k = 0; k < packet_lanes; ++k) f(k, k < n ? k : 0);
}

/// A packet's rays, structure of arrays: lane k holds ray k with its interval ending at
/// tmax[k]; lanes past the packet's rays hold a copy of ray 0 (the lane masks leave them out).
struct alignas(64) PacketRaySoa {
    float o[3][packet_lanes], d[3][packet_lanes], tmin[packet_lanes], tmax[packet_lanes];

    /// Lanes from rays[0, n) (for_lanes), lane k's interval ending at end(j).
    template <class End>
    [[gnu::always_inline]] void load(const Ray<float>* rays, int n, End&& end) {
        for_lanes(n, [&](int k, int j) __attribute__((always_inline)) {
            for (int a = 0; a < 3; ++a) o[a][k] = rays[j].origin[a], d[a][k] = rays[j].direction[a];
            tmin[k] = rays[j].tmin, tmax[k] = end(j);
        });
    }
};

/// The valid rays of a packet (wide_ray_valid) among its first n lanes as a lane mask,
/// whether they can share the packet traversal (at least packet_min_rays, one sign per axis,
/// tmin >= 0), and what for_sign_groups() splits them by.
struct PacketShape {
    unsigned lanes = 0;
    bool coherent = false;
    unsigned traceable = 0;  // valid lanes with tmin >= 0: those a packet may hold
    unsigned neg[3] = {};    // per axis, the lanes whose direction is negative
};

[[gnu::always_inline]] inline PacketShape packet_shape(const PacketRaySoa& r, int n) {
    unsigned neg[3] = {}, below = 0, valid = 0;
    for (int k = 0; k < packet_lanes; ++k) {
        const Ray<float> ray{{r.o[0][k], r.o[1][k], r.o[2][k]}, {r.d[0][k], r.d[1][k], r.d[2][k]}, r.tmin[k], r.tmax[k]};
        valid |= unsigned(wide_ray_valid(ray)) << k;
        for (int a = 0; a < 3; ++a) neg[a] |= unsigned(std::signbit(r.d[a][k])) << k;
        below |= unsigned(r.tmin[k] < 0.0f) << k;
    }
    PacketShape s;
    s.lanes = valid & ((1u << n) - 1u);
    bool same = (below & s.lanes) == 0;
    for (int a = 0; a < 3; ++a) same &= (neg[a] & s.lanes) == 0 || (neg[a] & s.lanes) == s.lanes;
    s.coherent = same && std::popcount(s.lanes) >= packet_min_rays;
    s.traceable = s.lanes & ~below;
    for (int a = 0; a < 3; ++a) s.neg[a] = neg[a];
    return s;
}

/// The first n lanes of s by direction signs: where the traceable lanes fall into at most
/// packet_max_groups sign classes, `packet(g)` for each class g of at least packet_min_rays
/// lanes (a coherent PacketShape); returns the other lanes, for the caller to trace alone.
template <class Packet>
[[gnu::always_inline]] inline unsigned for_sign_groups(const PacketShape& s, int n, Packet&& packet) {
    unsigned left = s.traceable, alone = (0xffffffffu >> (32 - n)) & ~left;
    int classes = 0;
    for (unsigned o = 0; o < 8; ++o) {
        unsigned m = left;
        for (int a = 0; a < 3; ++a) m &= (o >> a) & 1u ? s.neg[a] : ~s.neg[a];
        classes += m != 0;
    }
    if (classes > packet_max_groups) alone |= left, left = 0;
    while (left != 0) {
        const int k = std::countr_zero(left);
        unsigned g = left;
        for (int a = 0; a < 3; ++a) g &= (s.neg[a] >> k) & 1u ? s.neg[a] : ~s.neg[a];
        left &= ~g;
        if (std::popcount(g) < packet_min_rays) {
            alone |= g;
            continue;
        }
        PacketShape c = s;
        c.lanes = c.traceable = g;
        c.coherent = true;
        packet(c);
    }
    return alone;
}

/// Whether x is a normal float (std::isnormal).
[[gnu::always_inline]] inline bool normal_float(float x) {
    const float a = std::fabs(x);
    return a >= std::numeric_limits<float>::min() && a <= std::numeric_limits<float>::max();
}

/// What a coherent packet's interval test needs: the entry and exit plane rows per axis
/// (WideBvhNode::bounds; the signs of the packet's directions), the intervals of its origins
/// and reciprocal directions per axis, its smallest tmin, and `bounded` when every
/// reciprocal is a normal float (else no interval test).
struct PacketBounds {
    int near[3], far[3];
    float omin[3], omax[3], imin[3], imax[3], tmin_lo;
    bool bounded;

    /// The plane rows for the signs of lane `first`'s direction.
    [[gnu::always_inline]] void set_planes(const PacketRaySoa& r, int first) {
        for (int a = 0; a < 3; ++a) {
            const int neg = std::signbit(r.d[a][first]) ? 1 : 0;
            near[a] = 2 * a + neg;
            far[a] = 2 * a + 1 - neg;
        }
    }
    /// `bounded` from imin and imax: a coherent packet has one sign per axis, so every
    /// reciprocal lies between the two.
    [[gnu::always_inline]] void set_bounded() {
        bounded = true;
        for (int a = 0; a < 3; ++a) bounded = bounded && normal_float(imin[a]) && normal_float(imax[a]);
    }
};

/// The rays of one coherent packet as the portable box test reads them: origins and
/// reciprocal directions; lanes not in the packet hold a ray that enters nothing.
struct alignas(32) PacketRays : PacketBounds {
    float o[3][packet_lanes], inv[3][packet_lanes], tmin[packet_lanes];

    /// The rays `s.lanes` of r, a coherent packet (packet_shape).
    [[gnu::always_inline]] PacketRays(const PacketRaySoa& r, const PacketShape& s) {
        set_planes(r, std::countr_zero(s.lanes));
        constexpr float inf = infinity<float>;
        tmin_lo = inf;
        for (int a = 0; a < 3; ++a) omin[a] = imin[a] = inf, omax[a] = imax[a] = -inf;
        for (int k = 0; k < packet_lanes; ++k) {
            const bool in = (s.lanes >> k) & 1u;
            for (int a = 0; a < 3; ++a) {
                o[a][k] = in ? r.o[a][k] : 0.0f;
                inv[a][k] = in ? 1.0f / r.d[a][k] : 1.0f;
                if (!in) continue;
                omin[a] = std::min(omin[a], o[a][k]), omax[a] = std::max(omax[a], o[a][k]);
                imin[a] = std::min(imin[a], inv[a][k]), imax[a] = std::max(imax[a], inv[a][k]);
            }
            tmin[k] = in ? r.tmin[k] : inf;
            tmin_lo = std::min(tmin_lo, tmin[k]);
        }
        set_bounded();
    }
};

}  // namespace detail

}  // namespace glint
