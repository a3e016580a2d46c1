// benchmarks/support/user_meshes.hpp: bench_trees --user-meshes, glint as a user gets it
// (MeshBvh<MollerTrumbore<float>, 8>, default build options, threads = 1, closest_hit and
// any_hit single rays) against Embree 3 (rtcIntersect1 / rtcOccluded1, FTZ and DAZ set as
// Embree's documentation asks, build quality HIGH and MEDIUM) on every mesh of a folder.
// Passes alternate glint, Embree HIGH, Embree MEDIUM; the ratio printed is the median over
// passes of Embree's time / glint's (above 1: glint is faster). Hit counts are compared, and
// each ray's answer: where glint and Embree differ, whether the ray passes within 1e-5
// (barycentric, in double precision) of a triangle's edge, where two tests that are not
// watertight may both lose a hit through the crack between two triangles. Builds: --builds
// rounds (default 3) of glint on 1 and 2 threads, Embree HIGH and MEDIUM, medians printed.
#pragma once

#include <optional>
#include <string>

#include <glint/core/isa.hpp>

namespace glint::bench {

/// --isa NAME: sets `isa` to the kernels named; an error message (empty: none) for names
/// that are unknown or that this build and CPU cannot run.
inline std::string parse_isa(const std::string& name, std::optional<Isa>& isa) {
    isa = isa_from_name(name);
    if (!isa) {
        std::string names;
        for (Isa i : all_isas) names += std::string(names.empty() ? "" : ", ") + isa_name(i);
        return "unknown kernels '" + name + "' (" + names + ")";
    }
    if (!isa_supported(*isa)) return "this build and CPU cannot run the " + name + " kernels";
    return std::string();
}

}  // namespace glint::bench

#ifdef GLINT_HAVE_EMBREE
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <sys/resource.h>

#include <embree3/rtcore.h>

#include "support/clock.hpp"
#include "support/embree_scene.hpp"
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <glint/core/error.hpp>
#include <glint/core/isa.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "tree_scenes.hpp"

namespace glint::bench {

/// One Embree scene over a triangle soup, one build quality, one thread.
class EmbreeQ {
public:
    EmbreeQ(const std::vector<TriangleVertices<float>>& m, RTCBuildQuality q) {
        dev_ = rtcNewDevice("threads=1");
        if (!dev_) throw Error("rtcNewDevice failed");
        const auto t0 = std::chrono::steady_clock::now();
        scene_ = embree_triangle_scene(dev_, m, q);
        build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    ~EmbreeQ() {
        rtcReleaseScene(scene_);
        rtcReleaseDevice(dev_);
    }
    EmbreeQ(const EmbreeQ&) = delete;
    EmbreeQ& operator=(const EmbreeQ&) = delete;

    static RTCRay to_rtc(const Ray<float>& r) {
        RTCRay x{};
        x.org_x = r.origin.x, x.org_y = r.origin.y, x.org_z = r.origin.z;
        x.dir_x = r.direction.x, x.dir_y = r.direction.y, x.dir_z = r.direction.z;
        x.tnear = r.tmin, x.tfar = r.tmax, x.mask = 0xffffffffu;
        return x;
    }
    /// Embree's closest hit's triangle on r (-1 on a miss); whether r is occluded.
    long closest_id(const Ray<float>& r, RTCIntersectContext& ctx) const {
        RTCRayHit rh{};
        rh.ray = to_rtc(r);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &ctx, &rh);
        return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? long(rh.hit.primID) : -1;
    }
    bool is_occluded(const Ray<float>& r, RTCIntersectContext& ctx) const {
        RTCRay x = to_rtc(r);
        rtcOccluded1(scene_, &ctx, &x);
        return x.tfar < 0;  // Embree sets tfar to -inf when occluded
    }
    /// Over every ray: the number of closest hits (timed), or each ray's triangle (-1: miss).
    std::size_t closest(const std::vector<Ray<float>>& rays) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        std::size_t hits = 0;
        for (const auto& r : rays) hits += closest_id(r, ctx) >= 0;
        return hits;
    }
    std::vector<long> closest_ids(const std::vector<Ray<float>>& rays) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        std::vector<long> out;
        for (const auto& r : rays) out.push_back(closest_id(r, ctx));
        return out;
    }
    /// Over every ray: the number occluded (timed), or each ray's answer (1: occluded).
    std::size_t occluded(const std::vector<Ray<float>>& rays) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        std::size_t hits = 0;
        for (const auto& r : rays) hits += is_occluded(r, ctx);
        return hits;
    }
    std::vector<long> occluded_flags(const std::vector<Ray<float>>& rays) const {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        std::vector<long> out;
        for (const auto& r : rays) out.push_back(is_occluded(r, ctx));
        return out;
    }
    double build_s = 0;
    RTCScene scene() const { return scene_; }  ///< The committed scene (for packet queries).

private:
    RTCDevice dev_ = nullptr;
    RTCScene scene_ = nullptr;
};

struct UserMeshOptions {
    std::string scenes;            // --scenes DIR
    std::string only;              // --only STEM
    std::size_t rays = 200'000;    // incoherent and shadow rays
    int primary = 384;             // primary rays: primary x primary
    int reps = 5;                  // alternating passes
    int builds = 3;                // alternating builds (glint on 1 and 2 threads, Embree HIGH, MEDIUM)
    bool generated = true;         // also the generated scenes, reported apart
    std::optional<Isa> isa;        // --isa NAME: glint's kernels (default: best_isa())
};

/// One CSV row of the mode (bench_trees' columns plus api, embree_quality, query).
struct UserRow {
    std::string scene, query, quality;  // query: the ray set, or the packet call (user_packets.hpp)
    double glint_mrays = 0, embree_mrays = 0, ratio = 0, build_s = 0;
    std::size_t node_bytes = 0, triangles = 0;
};

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

/// Times one query: passes alternate glint, Embree HIGH, Embree MEDIUM; prints the median
/// ratios and the hit counts; appends two rows.
template <class G, class EH, class EM>
void user_query(const std::string& name, const char* query, std::size_t nrays, int reps, G&& glint, EH&& high,
                EM&& medium, std::size_t tris, double build_s, std::size_t bytes, std::vector<UserRow>& rows,
                bool& disagree) {
    using C = PassClock;  // wall or thread CPU time (--cpu-time)
    std::vector<double> tg, th, tm, rh, rm;
    std::size_t hg = 0, hh = 0, hm = 0;
    for (int p = 0; p < reps; ++p) {
        auto t0 = C::now();
        hg = glint();
        auto t1 = C::now();
        hh = high();
        auto t2 = C::now();
        hm = medium();
        auto t3 = C::now();
        tg.push_back(std::chrono::duration<double>(t1 - t0).count());
        th.push_back(std::chrono::duration<double>(t2 - t1).count());
        tm.push_back(std::chrono::duration<double>(t3 - t2).count());
        rh.push_back(th.back() / tg.back());
        rm.push_back(tm.back() / tg.back());
    }
    const bool same = hg == hh && hg == hm;
    disagree |= !same;
    std::printf("| %s | %s | %zu | %.3f | %.3f | %.3f | %zu / %zu / %zu%s |\n", name.c_str(), query, tris,
                median(tg) > 0 ? 1e-6 * double(nrays) / median(tg) : 0.0, median(rh), median(rm), hg, hh, hm,
                same ? "" : " DISAGREE");
    const double gm = 1e-6 * double(nrays) / median(tg);
    rows.push_back({name, query, "high", gm, 1e-6 * double(nrays) / median(th), median(rh), build_s, bytes, tris});
    rows.push_back({name, query, "medium", gm, 1e-6 * double(nrays) / median(tm), median(rm), build_s, bytes, tris});
}

/// Where ray r meets triangle t, in double precision: the smallest barycentric coordinate
/// (negative: outside) and the distance along the ray.
inline std::pair<double, double> barycentric_margin(const Ray<float>& r, const TriangleVertices<float>& t) {
    using D = glm::dvec3;
    const D o(r.origin), d(r.direction), a(t[0]), e1 = D(t[1]) - a, e2 = D(t[2]) - a;
    const D p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (det == 0.0) return {-1.0, 0.0};
    const D s = o - a, q = glm::cross(s, e1);
    const double u = glm::dot(s, p) / det, v = glm::dot(d, q) / det;
    return {std::min({u, v, 1.0 - u - v}), glm::dot(e2, q) / det};
}

/// Whether ray r, in double precision, crosses some triangle within its interval less than
/// `tol` (barycentric) from that triangle's boundary: where two float tests that are not
/// watertight (Möller-Trumbore's, Embree's) may each miss or hit the edge shared by two
/// triangles. Brute force: for the few rays on which glint and Embree differ.
inline bool near_edge(const Ray<float>& r, const std::vector<TriangleVertices<float>>& soup, double tol = 1e-5) {
    for (const auto& t : soup) {
        const auto [margin, d] = barycentric_margin(r, t);
        if (std::abs(margin) < tol && d > double(r.tmin) && d < double(r.tmax)) return true;
    }
    return false;
}

/// Whether triangles a and b meet ray r at the same distance (1e-6 relative, in double
/// precision): a tie of overlapping triangles, where either answer is right.
inline bool tie(const Ray<float>& r, const TriangleVertices<float>& a, const TriangleVertices<float>& b) {
    const double ta = barycentric_margin(r, a).second, tb = barycentric_margin(r, b).second;
    return std::abs(ta - tb) <= 1e-6 * std::max(std::abs(ta), std::abs(tb));
}

/// The rays on which glint's and Embree's answers differ (closest hit, `ids`: another
/// triangle or a hit against a miss; any hit: occluded or not), and how many of them pass
/// near a triangle's edge (near_edge) or are ties. Prints one line, and the first rays that
/// are neither.
inline void compare_rays(const std::string& name, const char* query, const std::vector<Ray<float>>& rays,
                         const std::vector<TriangleVertices<float>>& soup, const std::vector<long>& glint,
                         const std::vector<long>& embree, bool ids) {
    std::size_t differ = 0, edge = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        if (glint[i] == embree[i]) continue;
        ++differ;
        const bool both = ids && glint[i] >= 0 && embree[i] >= 0;
        if ((both && tie(rays[i], soup[std::size_t(glint[i])], soup[std::size_t(embree[i])])) ||
            near_edge(rays[i], soup)) {
            ++edge;
            continue;
        }
        const Ray<float>& r = rays[i];
        if (differ - edge <= 3)
            std::printf("#   %s %s ray %zu differs away from every edge: o=(%.9g %.9g %.9g) d=(%.9g %.9g %.9g) "
                        "glint %ld Embree %ld\n",
                        name.c_str(), query, i, r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y,
                        r.direction.z, glint[i], embree[i]);
    }
    std::printf("#   %s %s rays answered differently by glint and Embree HIGH: %zu of %zu, %zu of them ties or "
                "within 1e-5 of a triangle's edge\n",
                name.c_str(), query, differ, rays.size(), edge);
}

/// glint's nodes, leaves and triangle records per ray of one query.
inline void print_counts(const char* query, const WideBvhCounters& c, std::size_t rays) {
    const double n = double(rays);
    std::printf("#   glint per %s ray: %.1f nodes, %.2f leaves, %.1f records\n", query, double(c.nodes) / n,
                double(c.leaves) / n, double(c.records) / n);
}

}  // namespace glint::bench

#include "support/user_packets.hpp"

namespace glint::bench {

/// CPU seconds this process (who = RUSAGE_SELF) or this thread (RUSAGE_THREAD) has used.
inline double user_cpu_seconds(int who) {
    rusage u{};
    getrusage(who, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Runs every query on one mesh; returns its rows through `rows`.
inline void user_mesh(const std::string& name, const std::vector<TriangleVertices<float>>& soup,
                      const UserMeshOptions& opt, std::vector<UserRow>& rows, bool& disagree) {
    // As a user would: an indexed mesh over their vertex array.
    std::vector<float> pos(9 * soup.size());
    std::vector<std::uint32_t> idx(3 * soup.size());
    for (std::size_t i = 0; i < soup.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            for (int c = 0; c < 3; ++c) pos[9 * i + 3 * k + c] = soup[i][k][c];
            idx[3 * i + k] = std::uint32_t(3 * i + k);
        }
    const IndexedMesh<float> mesh{pos.data(), 3 * soup.size(), 3 * sizeof(float), idx.data(), soup.size()};
    // On a loaded machine the 2-thread wall time says little (no core is free): CPU time too,
    // the 2-thread build's split into this thread's and the other's (as the build table does).
    std::vector<double> bg, bg2, bh, bm, cpu1, main2, other2;
    double sah2 = 0;
    for (int p = 0; p < opt.builds; ++p) {  // builds alternate too
        for (unsigned threads : {1u, 2u}) {
            const double p0 = user_cpu_seconds(RUSAGE_SELF), m0 = user_cpu_seconds(RUSAGE_THREAD);
            const auto t0 = std::chrono::steady_clock::now();
            const MeshBvh<MollerTrumbore<float>, 8> b(mesh, {.threads = threads});
            (threads == 1 ? bg : bg2).push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
            const double pc = user_cpu_seconds(RUSAGE_SELF) - p0, mc = user_cpu_seconds(RUSAGE_THREAD) - m0;
            if (threads == 1) cpu1.push_back(pc);
            else sah2 = double(b.bvh().stats().sah_cost), main2.push_back(mc), other2.push_back(pc - mc);
        }
        bh.push_back(EmbreeQ(soup, RTC_BUILD_QUALITY_HIGH).build_s);
        bm.push_back(EmbreeQ(soup, RTC_BUILD_QUALITY_MEDIUM).build_s);
    }
    MeshBvh<MollerTrumbore<float>, 8> bvh(mesh, {.threads = 1});
    if (opt.isa) bvh.set_isa(*opt.isa);
    const EmbreeQ high(soup, RTC_BUILD_QUALITY_HIGH), medium(soup, RTC_BUILD_QUALITY_MEDIUM);
    std::printf("# %s build (median of %d): glint %.4f s (SAH %.4f), 2 threads %.4f s (x%.2f, SAH %.4f), Embree HIGH "
                "%.4f s, MEDIUM %.4f s (Embree SAH n/a); glint / HIGH %.2f, glint / MEDIUM %.2f\n",
                name.c_str(), opt.builds, median(bg), double(bvh.bvh().stats().sah_cost), median(bg2),
                median(bg) / median(bg2), sah2, median(bh), median(bm), median(bg) / median(bh), median(bg) / median(bm));
    std::printf("#   %s build CPU: 1 thread %.4f s, 2 threads %.4f + %.4f s (x%.2f at best)\n", name.c_str(), median(cpu1),
                median(main2), median(other2), median(cpu1) / std::max(median(main2), median(other2)));
    const std::span<const TriangleVertices<float>> s(soup);
    const auto incoherent = make_incoherent_rays<float>(s, opt.rays);
    const auto primary = make_primary_rays<float>(s, opt.primary, opt.primary);
    auto shadow = make_incoherent_rays<float>(s, opt.rays, 13);
    const AABB<float> box = mesh_bounds(s);
    const float cut = 0.2f * glm::length(box.extent());
    for (auto& r : shadow) r.tmax = cut;
    const std::size_t bytes = bvh.total_bytes();
    const double build = median(bg);
    for (auto [q, rays] : {std::pair{"incoherent", &incoherent}, std::pair{"primary", &primary}}) {
        const auto g = [&] {
            std::size_t h = 0;
            for (const auto& r : *rays) {
                StoreHit<float> hit;
                h += bvh.closest_hit(r, hit);
            }
            return h;
        };
        user_query(name, q, rays->size(), opt.reps, g, [&] { return high.closest(*rays); },
                   [&] { return medium.closest(*rays); }, soup.size(), build, bytes, rows, disagree);
        WideBvhCounters cnt;
        for (const auto& r : *rays) {
            StoreHit<float> hit;
            bvh.closest_hit(r, hit, cnt);
        }
        print_counts(q, cnt, rays->size());
        std::vector<long> ids;
        for (const auto& r : *rays) {
            StoreHit<float> hit;
            ids.push_back(bvh.closest_hit(r, hit) ? long(hit.id) : -1);
        }
        compare_rays(name, q, *rays, soup, ids, high.closest_ids(*rays), true);
    }
    const auto g = [&] {
        std::size_t h = 0;
        for (const auto& r : shadow) h += bvh.any_hit(r);
        return h;
    };
    user_query(name, "shadow", shadow.size(), opt.reps, g, [&] { return high.occluded(shadow); },
               [&] { return medium.occluded(shadow); }, soup.size(), build, bytes, rows, disagree);
    WideBvhCounters cnt;
    for (const auto& r : shadow) bvh.any_hit(r, cnt);
    print_counts("shadow", cnt, shadow.size());
    std::vector<long> occluded;
    for (const auto& r : shadow) occluded.push_back(bvh.any_hit(r));
    compare_rays(name, "shadow", shadow, soup, occluded, high.occluded_flags(shadow), false);
    user_packets(name, bvh, high, primary, box, opt.reps, rows, disagree, soup.size(), build);
}

/// Geometric mean of `ratio` over rows of one query and quality among `names`.
inline void print_geomeans(const char* label, const std::vector<UserRow>& rows, const std::vector<std::string>& names) {
    for (const char* q : {"incoherent", "primary", "shadow"})
        for (const char* e : {"high", "medium"}) {
            double s = 0;
            int n = 0;
            for (const auto& r : rows)
                if (r.query == q && r.quality == e && std::find(names.begin(), names.end(), r.scene) != names.end())
                    s += std::log(r.ratio), ++n;
            if (n) std::printf("# geomean %s %s Embree %s: %.3f x over %d scenes\n", label, q, e, std::exp(s / n), n);
        }
}

/// The mode: every .obj of opt.scenes (sorted), then the generated scenes apart.
inline std::vector<UserRow> run_user_meshes(
    const UserMeshOptions& opt, const std::function<std::vector<TriangleVertices<float>>(const std::string&)>& read) {
    namespace fs = std::filesystem;
    if (!fs::is_directory(opt.scenes))
        throw Error("--user-meshes: scenes folder '" + opt.scenes + "' not found (give --scenes DIR)");
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(opt.scenes))
        if (e.path().extension() == ".obj" && (opt.only.empty() || e.path().stem() == opt.only))
            files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    if (files.empty()) throw Error("--user-meshes: no .obj in '" + opt.scenes + "'");
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);  // as Embree's documentation asks
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    std::printf("# Embree %d.%d.%d, FTZ/DAZ on, threads=1; glint kernels %s (flags: %s); ratio = Embree time / "
                "glint time, median of %d alternating passes\n",
                RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH, isa_name(opt.isa.value_or(best_isa())),
                isa_name(compiled_isa), opt.reps);
    std::puts("| mesh | query | triangles | glint Mrays/s | x Embree HIGH | x Embree MEDIUM | hits glint / HIGH / MEDIUM |");
    std::puts("|---|---|---|---|---|---|---|");
    std::vector<UserRow> rows;
    std::vector<std::string> shared, generated;
    bool disagree = false;
    for (const auto& f : files) {
        const std::string name = fs::path(f).stem().string();
        user_mesh(name, read(f), opt, rows, disagree);
        shared.push_back(name);
    }
    if (opt.generated && opt.only.empty()) {
        user_mesh("torus-knot", make_torus_knot<float>(), opt, rows, disagree);
        user_mesh("stadium", make_teapot_in_stadium<float>(), opt, rows, disagree);
        generated = {"torus-knot", "stadium"};
    }
    print_geomeans("shared", rows, shared);
    print_geomeans("generated", rows, generated);
    if (disagree) std::puts("# WARNING: hit counts disagree with Embree on some rows (DISAGREE above)");
    return rows;
}

/// Writes the mode's rows as CSV: bench_trees' columns plus api, embree_quality and query.
inline void write_user_csv(const std::string& path, const std::vector<UserRow>& rows) {
    std::ofstream out(path);
    if (!out) throw Error("cannot write '" + path + "'");
    out << "scene,rays,tree,layout,intersector,mrays_per_s,build_s,node_bytes,bytes_per_triangle,embree_mrays_per_s,"
           "build_threads,api,embree_quality,query\n";
    for (const auto& r : rows)
        out << r.scene << ',' << r.query << ",bvh8,soa,moller-trumbore," << r.glint_mrays << ',' << r.build_s << ','
            << r.node_bytes << ',' << double(r.node_bytes) / double(r.triangles) << ',' << r.embree_mrays
            << ",1,meshbvh," << r.quality << ','
            << (r.query.ends_with("_packet") ? r.query : r.query == "shadow" ? "any_hit" : "closest_hit") << '\n';
    std::printf("# wrote %s (%zu rows)\n", path.c_str(), rows.size());
}

}  // namespace glint::bench
#endif
