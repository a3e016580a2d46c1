// bench_photons: the photon map's kd-tree (photons/photon_map.hpp) and several maps per
// surface group (photons/surface_groups.hpp) against Larsen 2004's Tables 8.1 and 8.2, and
// the kNN query against nanoflann, the peer a user would pick for kNN in 3D.
//
// Table 8.1 (Larsen 2004, §8.2): 10^6 random photons (uniform in the unit cube, 20 bytes
// here, 40 in Larsen's) shared at random among M = 1, 10, 100, 1000 maps; the time to
// balance all M maps, and the time of a 500-nearest lookup in a random one of the maps at a
// random point (the average over `queries` lookups). Larsen: balancing 5.05, 3.08, 0.70,
// 0.55 s; lookup 332, 291, 213, 116 us. Printed as ratios to M = 1 beside Larsen's ratios.
// Table 8.2: a scene of 50 000 stored photons (the Cornell box's global map, truncated):
// balancing and precomputing irradiance at every 4th photon, one map against one map per
// surface group (alpha = 30 degrees). Larsen: balancing 0.56 -> 0.08 s, irradiance 13.80 ->
// 5.88 s. Everything on one thread.
// kNN against nanoflann (KDTreeSingleIndexAdaptor, L2_Simple, leaf size 10, its knnSearch)
// on the same photons (10^4, 10^5, 10^6), the same random query points, k = 50 and 500, single thread,
// the two alternating for `passes` passes; glint queries with an unbounded radius. Printed:
// microseconds per query and glint's speed / nanoflann's; the sums of the found squared
// distances must agree.
//
// Emission: random against Halton emission (PhotonEmission), the RMS error of a closed-form
// quantity (a point light's direct power onto a floor) over 16 seeds.
//
// Usage: bench_photons [--quick] [--photons N] [--queries Q] [--passes P] [--seed S] [--knn-only] [--emission-only]
// --quick: 20 000 photons, M = 1 and 10, 5 000 scene photons, 200 queries, 1 pass.
// --photons N: N photons for Table 8.1 and the kNN comparison; --knn-only, --emission-only:
// that section alone.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <span>
#include <string>
#include <vector>

#if __has_include(<nanoflann.hpp>)
#include <nanoflann.hpp>
#define GLINT_HAVE_NANOFLANN 1
#endif

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/photons/photon_map.hpp>
#include <glint/photons/photon_tracing.hpp>
#include <glint/photons/radiance_estimate.hpp>
#include <glint/photons/surface_groups.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "flags.hpp"  // cli/: the command-line conventions
#include "support/clock.hpp"

using namespace glint;
using bench::seconds_since;
using Clock = std::chrono::steady_clock;

namespace {

struct Options {
    std::size_t photons = 1000000, scene_photons = 50000, queries = 20000;
    std::vector<std::size_t> maps{1, 10, 100, 1000};
    std::vector<std::size_t> knn_sizes{10000, 100000, 1000000};
    std::vector<std::size_t> emission_photons{1000, 10000, 100000};
    int passes = 5;
    std::uint64_t seed = 1;
};

Options parse(int argc, char** argv) {
    Options o;
    cli::App app("bench_photons: the photon maps' balancing and k nearest neighbours (Larsen 2004, ch. 8) against "
                 "nanoflann, and photon emission");
    // --quick and the section flags first: --photons and the counts after them in this list override them.
    app.flag("--quick", [&o] {
        o.photons = 20000, o.scene_photons = 5000, o.queries = 200, o.maps = {1, 10}, o.passes = 1, o.knn_sizes = {20000};
        o.emission_photons = {1000};
    }, "a smoke run");
    app.flag("--knn-only", [&o] { o.maps.clear(), o.scene_photons = 0, o.emission_photons.clear(); },
             "only the kNN rows against nanoflann");
    app.flag("--emission-only", [&o] { o.maps.clear(), o.scene_photons = 0, o.knn_sizes.clear(); }, "only the emission rows");
    cli::number_to<std::size_t>(app, "--photons", [&o](std::size_t n) { o.photons = n, o.knn_sizes = {n}; }, 1000, 100000000,
                                "photons per map (and the one kNN size; default 1000000)");
    cli::number(app, "--queries", o.queries, std::size_t(1), std::size_t(100000000), "kNN queries");
    cli::number(app, "--passes", o.passes, 1, 1000, "timed passes");
    cli::number(app, "--seed", o.seed, std::uint64_t(0), ~std::uint64_t(0), "random seed");
    if (!cli::parse(app, argc, argv)) std::exit(0);
    return o;
}

std::vector<Photon> random_photons(std::size_t n, Pcg32& rng) {
    std::vector<Photon> out(n);
    for (Photon& p : out) {
        const float x = rng.uniform<float>(), y = rng.uniform<float>(), z = rng.uniform<float>();
        p = Photon(Vec3<float>(x, y, z), Rgb<float>(1.0f / float(n)), Vec3<float>(0, 0, -1), Vec3<float>(0, 0, 1));
    }
    return out;
}

std::vector<Vec3<float>> random_points(std::size_t n, Pcg32& rng) {
    std::vector<Vec3<float>> out(n);
    for (auto& p : out) {
        const float x = rng.uniform<float>(), y = rng.uniform<float>(), z = rng.uniform<float>();
        p = Vec3<float>(x, y, z);
    }
    return out;
}

/// Table 8.1's row for M maps: balancing seconds and microseconds per 500-nearest lookup.
std::pair<double, double> table_8_1_row(const std::vector<Photon>& photons, std::size_t maps, const Options& o) {
    Pcg32 rng(o.seed, maps);
    std::vector<std::vector<Photon>> parts(maps);
    for (const Photon& p : photons) parts[rng.bounded(std::uint32_t(maps))].push_back(p);
    const auto t0 = Clock::now();
    const GroupedPhotonMaps grouped(parts, std::vector<std::uint32_t>(maps), 1);  // group_of: unused here
    const double balance = seconds_since(t0);
    const std::vector<Vec3<float>> points = random_points(o.queries, rng);
    std::vector<std::uint32_t> which(o.queries);
    for (auto& w : which) w = rng.bounded(std::uint32_t(maps));
    std::vector<PhotonNeighbour> out;
    double check = 0;
    const auto t1 = Clock::now();
    for (std::size_t q = 0; q < o.queries; ++q) {
        grouped.group(which[q]).knn(points[q], 500, std::numeric_limits<float>::infinity(), out);
        check += out.empty() ? 0.0 : double(out.front().d2);
    }
    const double lookup = seconds_since(t1) / double(o.queries) * 1e6;
    if (check < 0) std::printf("impossible\n");
    return {balance, lookup};
}

void table_8_1(const Options& o) {
    Pcg32 rng(o.seed);
    const std::vector<Photon> photons = random_photons(o.photons, rng);
    const double larsen_balance[4] = {5.05, 3.08, 0.70, 0.55}, larsen_lookup[4] = {332, 291, 213, 116};
    std::printf("\n# Table 8.1: %zu random photons in M maps, one thread; 500-nearest lookups, %zu queries\n", o.photons, o.queries);
    std::printf("%6s %12s %10s %10s %12s %10s %10s\n", "M", "balance_s", "ratio", "Larsen", "lookup_us", "ratio", "Larsen");
    double b1 = 0, l1 = 0;
    for (std::size_t i = 0; i < o.maps.size(); ++i) {
        const auto [b, l] = table_8_1_row(photons, o.maps[i], o);
        if (i == 0) b1 = b, l1 = l;
        std::printf("%6zu %12.4f %10.3f %10.3f %12.2f %10.3f %10.3f\n", o.maps[i], b, b / b1, larsen_balance[i] / larsen_balance[0],
                    l, l / l1, larsen_lookup[i] / larsen_lookup[0]);
    }
}

void table_8_2(const Options& o) {
    const Scene<float> s = builtin_scene<float>("cornell");
    const MeshBvh<MollerTrumbore<float>, 8> accel(s.triangles);
    PhotonSet set = trace_photons(s, accel, PhotonSettings{.photons = o.scene_photons, .seed = o.seed, .threads = 1});
    set.global.resize(std::min(set.global.size(), o.scene_photons));
    set.global_triangle.resize(set.global.size());
    const SurfaceGroups groups = surface_groups(std::span<const TriangleVertices<float>>(s.triangles), 30.0f * pi<float> / 180.0f);
    const RadianceEstimateSettings est{.k = 100, .max_radius = 0.2f};
    auto t0 = Clock::now();
    const PhotonMap one(set.global);
    const double b1 = seconds_since(t0);
    t0 = Clock::now();
    const PrecomputedIrradiance e1(one, est, 1);
    const double i1 = seconds_since(t0);
    t0 = Clock::now();
    const GroupedPhotonMaps many(set.global, set.global_triangle, groups, 1);
    const double bm = seconds_since(t0);
    t0 = Clock::now();
    std::size_t precomputed = 0;
    for (std::size_t g = 0; g < many.groups(); ++g) precomputed += PrecomputedIrradiance(many.group(g), est, 1).size();
    const double im = seconds_since(t0);
    std::printf("\n# Table 8.2: the Cornell box's global map, %zu photons, %zu surface groups (alpha 30 deg), one thread;"
                " irradiance from k = %zu within %.2f at every 4th photon (%zu and %zu points)\n",
                set.global.size(), groups.count, est.k, double(est.max_radius), e1.size(), precomputed);
    std::printf("%12s %12s %12s %10s %10s\n", "", "one_map_s", "groups_s", "ratio", "Larsen");
    std::printf("%12s %12.4f %12.4f %10.3f %10.3f\n", "balancing", b1, bm, bm / b1, 0.08 / 0.56);
    std::printf("%12s %12.4f %12.4f %10.3f %10.3f\n", "irradiance", i1, im, im / i1, 5.88 / 13.80);
}

/// Quasi-random emission: the direct power a point light sends onto the floor of a closed
/// black cube (closed form: I times the floor's solid angle, four corner rectangles of
/// sides a, b at distance d, atan(a b / (d sqrt(d^2 + a^2 + b^2))) each), estimated from the
/// photons stored on the floor; RMS relative error over 16 seeds, random against Halton.
void emission_error(const Options& o) {
    Scene<float> s;
    const auto black = s.add_material(Material<float>::lambertian(Rgb<float>(0.0f)));
    using V = Vec3<float>;
    const V c(0);
    detail::add_quad_facing(s, V(-1, -1, -1), V(1, -1, -1), V(1, -1, 1), V(-1, -1, 1), c, black);  // floor: triangles 0, 1
    detail::add_quad_facing(s, V(-1, 1, -1), V(-1, 1, 1), V(1, 1, 1), V(1, 1, -1), c, black);
    detail::add_quad_facing(s, V(-1, -1, -1), V(-1, 1, -1), V(1, 1, -1), V(1, -1, -1), c, black);
    detail::add_quad_facing(s, V(-1, -1, 1), V(1, -1, 1), V(1, 1, 1), V(-1, 1, 1), c, black);
    detail::add_quad_facing(s, V(-1, -1, -1), V(-1, -1, 1), V(-1, 1, 1), V(-1, 1, -1), c, black);
    detail::add_quad_facing(s, V(1, -1, -1), V(1, 1, -1), V(1, 1, 1), V(1, -1, 1), c, black);
    s.point_lights.push_back(PointLight<float>::isotropic(V(0.1f, 0.5f, -0.2f), Rgb<float>(1.0f)));
    const MeshBvh<MollerTrumbore<float>, 8> accel(s.triangles);
    const double d = 1.5;
    double omega = 0;
    for (const double a : {1.1, 0.9})
        for (const double b : {0.8, 1.2}) omega += std::atan(a * b / (d * std::sqrt(d * d + a * a + b * b)));
    std::printf("\n# Emission: a point light's direct power onto a closed black cube's floor (exact %.6f), RMS relative error over 16 seeds\n", omega);
    std::printf("%9s %12s %12s %14s\n", "photons", "random", "halton", "random/halton");
    for (const std::size_t n : o.emission_photons) {
        double e2[2] = {0, 0};
        for (std::uint64_t seed = 1; seed <= 16; ++seed)
            for (int m = 0; m < 2; ++m) {
                const PhotonSet set = trace_photons(s, accel, PhotonSettings{.photons = n, .seed = seed, .threads = 1,
                    .emission = m ? PhotonEmission::halton : PhotonEmission::random});
                double floor = 0;
                for (std::size_t i = 0; i < set.global.size(); ++i)
                    if (set.global_triangle[i] < 2) floor += set.global[i].power()[0];
                e2[m] += (floor / omega - 1) * (floor / omega - 1) / 16;
            }
        std::printf("%9zu %12.5f %12.5f %14.2f\n", n, std::sqrt(e2[0]), std::sqrt(e2[1]), std::sqrt(e2[0] / e2[1]));
    }
}

#ifdef GLINT_HAVE_NANOFLANN
/// nanoflann's view of the photons: positions through the adaptor interface it asks for.
struct PhotonCloud {
    const std::vector<Photon>& photons;
    std::size_t kdtree_get_point_count() const { return photons.size(); }
    float kdtree_get_pt(std::size_t i, std::size_t dim) const { return photons[i].position[int(dim)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const { return false; }
};
using NanoTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PhotonCloud>, PhotonCloud, 3>;

void versus_nanoflann(const Options& o, std::size_t size) {
    Pcg32 rng(o.seed + 7);
    const std::vector<Photon> photons = random_photons(size, rng);
    const std::vector<Vec3<float>> points = random_points(o.queries, rng);
    const PhotonMap map(photons);
    const PhotonCloud cloud{photons};
    NanoTree nano(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    nano.buildIndex();
    std::printf("\n# kNN against nanoflann %d.%d.%d: %zu photons uniform in the unit cube, %zu random queries, one thread, %d alternating passes\n",
                NANOFLANN_VERSION >> 8, (NANOFLANN_VERSION >> 4) & 15, NANOFLANN_VERSION & 15, size, o.queries, o.passes);
    std::printf("%6s %12s %14s %16s %8s\n", "k", "glint_us", "nanoflann_us", "glint/nanoflann", "same");
    for (const std::size_t k : {std::size_t(50), std::size_t(500)}) {
        std::vector<PhotonNeighbour> out;
        std::vector<std::uint32_t> idx(k);
        std::vector<float> d2(k);
        double tg = 0, tn = 0, sg = 0, sn = 0;
        for (int pass = 0; pass < o.passes; ++pass) {
            auto t0 = Clock::now();
            for (const auto& x : points) {
                map.knn(x, k, std::numeric_limits<float>::infinity(), out);
                for (const PhotonNeighbour& q : out) sg += q.d2;
            }
            tg += seconds_since(t0);
            t0 = Clock::now();
            for (const auto& x : points) {
                const float q[3] = {x.x, x.y, x.z};
                const std::size_t found = nano.knnSearch(q, k, idx.data(), d2.data());
                for (std::size_t i = 0; i < found; ++i) sn += d2[i];
            }
            tn += seconds_since(t0);
        }
        const double n = double(points.size()) * o.passes;
        const bool same = std::abs(sg - sn) <= 1e-5 * std::max(sg, sn);
        std::printf("%6zu %12.3f %14.3f %16.3f %8s\n", k, tg / n * 1e6, tn / n * 1e6, tn / tg, same ? "yes" : "NO");
    }
}
#endif

}  // namespace

int main(int argc, char** argv) {
    try {
        const Options o = parse(argc, argv);
        std::printf("# bench_photons (timings single-threaded; ratios from the same run)\n");
        if (!o.maps.empty()) table_8_1(o);
        if (o.scene_photons > 0) table_8_2(o);
        if (!o.emission_photons.empty()) emission_error(o);
#ifdef GLINT_HAVE_NANOFLANN
        for (const std::size_t size : o.knn_sizes) versus_nanoflann(o, size);
#else
        std::printf("\n# nanoflann not found: the kNN comparison is skipped\n");
#endif
    } catch (const Error& e) {
        std::fprintf(stderr, "bench_photons: %s\n", e.what());
        return 2;
    }
    return 0;
}
