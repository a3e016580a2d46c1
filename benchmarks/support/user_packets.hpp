// benchmarks/support/user_packets.hpp: bench_trees --user-meshes' packet rows: MeshBvh's ray
// streams (closest_hit / any_hit over spans, 8-ray packets where coherent) against glint's own
// single-ray loop and Embree 3's 16-ray packets (rtcIntersect16 / rtcOccluded16, valid masks,
// the context flagged coherent, scene quality HIGH), on primary rays and on shadow rays from
// the primary rays' hit points (pixel order) to one point light above the mesh. Passes
// alternate glint single rays, glint streams, Embree packets, Embree single rays; ratios are
// medians over passes. FTZ/DAZ are set by the caller (user_meshes.hpp) for all of them.
#pragma once

#ifdef GLINT_HAVE_EMBREE
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <embree3/rtcore.h>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/trees/mesh_bvh.hpp>

namespace glint::bench {

/// Rays [i, i + 16) of `rays` (fewer at the end) as one Embree packet; valid[k] = -1 for the
/// lanes in use.
inline void embree_packet(const std::vector<Ray<float>>& rays, std::size_t i, RTCRay16& x, int* valid) {
    for (int k = 0; k < 16; ++k) {
        valid[k] = i + std::size_t(k) < rays.size() ? -1 : 0;
        const Ray<float>& r = rays[valid[k] ? i + std::size_t(k) : i];
        x.org_x[k] = r.origin.x, x.org_y[k] = r.origin.y, x.org_z[k] = r.origin.z;
        x.dir_x[k] = r.direction.x, x.dir_y[k] = r.direction.y, x.dir_z[k] = r.direction.z;
        x.tnear[k] = r.tmin, x.tfar[k] = r.tmax, x.time[k] = 0.0f;
        x.mask[k] = 0xffffffffu, x.id[k] = unsigned(k), x.flags[k] = 0;
    }
}

/// Embree's 16-ray packets over `rays`: the closest hits (Any = false) or occluded rays.
template <bool Any>
std::size_t embree16(RTCScene scene, const std::vector<Ray<float>>& rays) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) int valid[16];
    const auto rh = std::make_unique<RTCRayHit16>();  // 64-byte aligned type
    std::size_t hits = 0;
    for (std::size_t i = 0; i < rays.size(); i += 16) {
        embree_packet(rays, i, rh->ray, valid);
        if constexpr (Any) {
            rtcOccluded16(valid, scene, &ctx, &rh->ray);
            for (int k = 0; k < 16; ++k) hits += valid[k] && rh->ray.tfar[k] < 0.0f;
        } else {
            std::fill(std::begin(rh->hit.geomID), std::end(rh->hit.geomID), RTC_INVALID_GEOMETRY_ID);
            rtcIntersect16(valid, scene, &ctx, rh.get());
            for (int k = 0; k < 16; ++k) hits += valid[k] && rh->hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
        }
    }
    return hits;
}

/// One packet row: glint single rays, glint stream, Embree packets, Embree single rays,
/// alternating; prints the ratios, the hit counts, per-ray counts, and appends a row.
template <bool Any, class EmbreeOne>
void packet_query(const std::string& name, const char* query, const MeshBvh<MollerTrumbore<float>, 8>& bvh,
                  RTCScene scene, EmbreeOne&& embree1, const std::vector<Ray<float>>& rays, int reps,
                  std::vector<UserRow>& rows, bool& disagree, std::size_t tris, double build_s) {
    using C = PassClock;  // wall or thread CPU time (--cpu-time)
    std::vector<StoreHit<float>> hits(rays.size());
    const std::unique_ptr<bool[]> occ(new bool[rays.size()]);
    const auto single = [&] {
        std::size_t h = 0;
        for (const auto& r : rays) {
            StoreHit<float> hit;
            h += Any ? bvh.any_hit(r) : bvh.closest_hit(r, hit);
        }
        return h;
    };
    const auto stream = [&] {
        if constexpr (Any) return bvh.any_hit(rays, std::span<bool>(occ.get(), rays.size()));
        else return bvh.closest_hit(rays, hits);
    };
    std::vector<double> vs_single, vs_e16, vs_e1, tp;
    std::size_t hs = 0, hp = 0, h16 = 0, h1 = 0;
    for (int p = 0; p < reps; ++p) {
        std::fill(hits.begin(), hits.end(), StoreHit<float>{});
        const auto t0 = C::now();
        hs = single();
        const auto t1 = C::now();
        hp = stream();
        const auto t2 = C::now();
        h16 = embree16<Any>(scene, rays);
        const auto t3 = C::now();
        h1 = embree1();
        const auto t4 = C::now();
        const double packet = std::chrono::duration<double>(t2 - t1).count();
        tp.push_back(packet);
        vs_single.push_back(std::chrono::duration<double>(t1 - t0).count() / packet);
        vs_e16.push_back(std::chrono::duration<double>(t3 - t2).count() / packet);
        vs_e1.push_back(std::chrono::duration<double>(t4 - t3).count() / packet);
    }
    const bool same = hs == hp && hp == h16 && hp == h1;
    disagree |= !same;
    const double mrays = 1e-6 * double(rays.size()) / median(tp);
    std::printf("| %s | %s | %zu | %.3f | x glint single %.3f | x Embree16 HIGH %.3f | x Embree1 HIGH %.3f | "
                "%zu / %zu / %zu / %zu%s |\n",
                name.c_str(), query, rays.size(), mrays, median(vs_single), median(vs_e16), median(vs_e1), hp, hs, h16,
                h1, same ? "" : " DISAGREE");
    WideBvhCounters one, packed;
    for (const auto& r : rays) {
        StoreHit<float> hit;
        Any ? bvh.any_hit(r, one) : bvh.closest_hit(r, hit, one);
    }
    if constexpr (Any) bvh.any_hit(rays, std::span<bool>(occ.get(), rays.size()), packed);
    else {
        std::fill(hits.begin(), hits.end(), StoreHit<float>{});
        bvh.closest_hit(rays, hits, packed);
    }
    const double n = double(rays.size());
    std::printf("#   %s %s per ray: single %.1f nodes %.2f leaves; packets %.1f ray-node tests, %.2f node visits "
                "(%.1f rays per visit), %.2f leaves\n",
                name.c_str(), query, double(one.nodes) / n, double(one.leaves) / n, double(packed.nodes) / n,
                double(packed.packets) / n, double(packed.nodes) / double(std::max<std::uint64_t>(packed.packets, 1)),
                double(packed.leaves) / n);
    rows.push_back({name, query, "high", mrays, mrays / median(vs_e16), median(vs_e16), build_s, 0, tris});
}

/// Both packet rows of one mesh.
template <class EmbreeHigh>
void user_packets(const std::string& name, const MeshBvh<MollerTrumbore<float>, 8>& bvh, const EmbreeHigh& high,
                  const std::vector<Ray<float>>& primary, const AABB<float>& box, int reps, std::vector<UserRow>& rows,
                  bool& disagree, std::size_t tris, double build_s) {
    packet_query<false>(name, "closest_hit_packet", bvh, high.scene(), [&] { return high.closest(primary); }, primary,
                        reps, rows, disagree, tris, build_s);
    const std::vector<Ray<float>> shadow = make_light_shadow_rays(primary, box, [&](const Ray<float>& r, float& t) {
        StoreHit<float> h;
        const bool hit = bvh.closest_hit(r, h);
        t = h.t;
        return hit;
    });
    packet_query<true>(name, "any_hit_packet", bvh, high.scene(), [&] { return high.occluded(shadow); }, shadow, reps,
                       rows, disagree, tris, build_s);
}

}  // namespace glint::bench
#endif
