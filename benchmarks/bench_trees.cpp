// bench_trees: ray-shooting throughput of glint's trees (Szécsi 2009, §4.2-4.4) against
// Embree 3's rtcIntersect1 on the very same rays, single thread.
//
//   bench_trees [--mesh FILE.obj]... [--csv FILE] [--quick] [--rays N] [--reps N]
//               [--no-generated] [--only SCENE] [--all | --few] [--memory]
//
// For every scene (generated: the 2880-triangle torus knot of Szécsi 2009, §5, "teapot in a
// stadium", a 128k-triangle torus knot; plus each --mesh) and two ray sets (primary camera
// rays; incoherent diffuse rays leaving surface points on both sides), it builds every
// tree x layout x intersector combination, traces every ray for its closest hit and prints
// Mrays/s (best of --reps passes, default 3; 1 with --quick), build time, node memory and the
// ratio to Embree: Embree is timed on the same rays alternately with every pass of every
// combination, and the printed ratio is the median over passes of (Embree's time / ours),
// each pair adjacent in time, so that both see the same machine load. (The CSV's
// embree_mrays_per_s is Embree's best pass.)
// --csv writes scene,rays,tree,layout,intersector,mrays_per_s,build_s,node_bytes,
// bytes_per_triangle,embree_mrays_per_s,build_threads (embree_mrays_per_s is empty without
// Embree; build_threads is the wide BVH's build threads, 1 for the kd-tree and BIH).
// The wide BVH (trees/mesh_bvh.hpp) runs as tree bvh8 / bvh4, layout soa, built on one
// thread; --wide runs only it (every intersector, 8 and 4 wide) and prints its build time
// on 1 and 2 threads next to Embree's (threads=1) and its bytes per triangle next to
// Embree's (from Embree's memory monitor); --cpu-time times trace passes by the thread's
// CPU time instead of wall time (both peers alike); --wide --few: only bvh8 with Moller-Trumbore
// (float child boxes, layout soa; --quantized adds quantized boxes, soa-q8, which every run
// without --few includes); --no-build-table skips the build timing. --bvh-ct / --bvh-ci / --bvh-block /
// --bvh-leaf / --bvh-bins / --bvh-cn set its SAH constants (BvhBuildOptions; --bvh-cn: C_N of the
// wide collapse); --build-threads N builds the
// timed trees on N threads (the CSV's build_threads); --bvh-siblings 1 places a node's inner
// children side by side (WideNodeOrder::sibling_blocks); --compact-subtrees adds bvh8 and bvh4
// (Moller-Trumbore) in Szécsi 2009's compact subtrees of 4 KiB (WideCompactSubtrees<18> and <36>,
// layout soa-compact18 / soa-compact36) and bvh4 in the collapse's order. --sbvh adds the 8-wide BVH with
// spatial splits (BvhBuildOptions::spatial_splits; tree sbvh8, Moller-Trumbore, paired with
// Embree like every row) and prints its references and build time, then times it against
// bvh8 directly (passes alternating, median ratio); --sbvh-alpha and --sbvh-budget set its
// overlap threshold and reference budget.
// --quick: fewer rays, the knot and the meshes only, pointer and compact-31 only (CI smoke).
// --all: every layout (pointer, havran-K and compact-K for K = 3 ... 63); --few: pointer and
// compact-31 only (as --quick, with the full ray count).
// --solo glint|embree: trace with bvh8 (Moller-Trumbore) or Embree alone, --reps passes, no
// timing or build table (for valgrind --tool=cachegrind).
// --set primary|incoherent: run one ray set. --big adds knot-2m, a 2,048,000-triangle torus knot.
// --only SCENE: run one scene (by name: torus-knot, stadium, knot-128k, or a mesh's file stem).
// --memory: print only the node-memory table (pointer, havran-K, compact-K for K = 3 ... 63,
// kd-tree and BIH; Szécsi 2009, Fig. 4.6) and exit.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <sys/resource.h>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/wald.hpp>
#include <glint/intersection/watertight.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/trees/traversal.hpp>

#include "flags.hpp"  // cli/: the command-line conventions
#include "support/embree_scene.hpp"
#include "support/intersector_names.hpp"
#include "support/obj_reader.hpp"  // bench::read_obj
#include "support/user_meshes.hpp"
#include "tree_scenes.hpp"

#ifdef GLINT_HAVE_EMBREE
#include <embree3/rtcore.h>
#endif

using namespace glint;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// The time a trace pass is measured by: wall time, or with --cpu-time this thread's CPU
/// time (on a shared machine the wall time counts the time slices other processes take).
bool use_cpu_time = false;
double pass_clock() {
    if (!use_cpu_time) return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// Seconds of one closest-hit pass of `acc` over `rays` (pass_clock).
template <class Accel>
double closest_hit_pass(const Accel& acc, const std::vector<Ray<float>>& rays) {
    std::size_t hits = 0;
    const double t0 = pass_clock();
    for (const auto& r : rays) {
        StoreHit<float> h;
        hits += acc.closest_hit(r, h);
    }
    const double t = pass_clock() - t0;
    if (hits == std::size_t(-1)) std::puts("");  // keep the loop
    return t;
}

/// The table's labels: the library's types carry none (intersectors: support/intersector_names.hpp).
std::string layout_label(std::type_identity<PointerLayout>) { return "pointer"; }
template <std::uint32_t K>
std::string layout_label(std::type_identity<HavranSubtrees<K>>) { return "havran-" + std::to_string(K); }
template <std::uint32_t K>
std::string layout_label(std::type_identity<CompactSubtrees<K>>) { return "compact-" + std::to_string(K); }
/// The wide BVH's layout column: the box format, then the node layout if not the collapse's order.
template <WideBoxes B>
std::string wide_layout_label(std::type_identity<WideBuildOrder>) { return B == WideBoxes::floats ? "soa" : "soa-q8"; }
template <WideBoxes B, std::uint32_t K>
std::string wide_layout_label(std::type_identity<WideCompactSubtrees<K>>) {
    return wide_layout_label<B>(std::type_identity<WideBuildOrder>{}) + "-compact" + std::to_string(K);
}

struct RaySet {
    std::string name;
    std::vector<Ray<float>> rays;
};

struct Scene {
    std::string name;
    Mesh<float> mesh;
    std::vector<RaySet> sets;
};

#ifdef GLINT_HAVE_EMBREE
class Embree {
public:
    explicit Embree(const Mesh<float>& m) {
        device_ = rtcNewDevice("threads=1");
        if (!device_) throw Error("rtcNewDevice failed");
        rtcSetDeviceMemoryMonitorFunction(
            device_,
            [](void* user, ssize_t delta, bool) {
                *static_cast<long long*>(user) += delta;
                return true;
            },
            &bytes);
        const auto t0 = Clock::now();
        scene_ = bench::embree_triangle_scene(device_, m, RTC_BUILD_QUALITY_MEDIUM);  // Embree's default
        build_seconds = seconds_since(t0);
    }
    ~Embree() {
        rtcReleaseScene(scene_);
        rtcReleaseDevice(device_);
    }
    Embree(const Embree&) = delete;
    Embree& operator=(const Embree&) = delete;

    /// Closest-hit t per ray (inf for a miss).
    void trace(const std::vector<Ray<float>>& rays, std::vector<float>& t) const {
        t.resize(rays.size());
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        for (std::size_t i = 0; i < rays.size(); ++i) {
            const Ray<float>& r = rays[i];
            RTCRayHit rh;
            rh.ray.org_x = r.origin.x;
            rh.ray.org_y = r.origin.y;
            rh.ray.org_z = r.origin.z;
            rh.ray.dir_x = r.direction.x;
            rh.ray.dir_y = r.direction.y;
            rh.ray.dir_z = r.direction.z;
            rh.ray.tnear = r.tmin;
            rh.ray.tfar = r.tmax;
            rh.ray.time = 0;
            rh.ray.mask = 0xffffffffu;
            rh.ray.id = 0;
            rh.ray.flags = 0;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(scene_, &ctx, &rh);
            t[i] = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? rh.ray.tfar : infinity<float>;
        }
    }
    double build_seconds = 0;
    long long bytes = 0;  // held by the device after the build (its memory monitor)

private:
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
};
#endif

#ifdef GLINT_HAVE_EMBREE
using Peer = Embree;
#else
struct Peer {  // no peer: never constructed
    void trace(const std::vector<Ray<float>>&, std::vector<float>&) const {}
};
#endif

struct Options {
    std::vector<std::string> meshes;
    std::string csv, only, set;  // --set: run one ray set (primary or incoherent)
    std::string solo;            // --solo glint|embree: trace with one of them only (profiling)
    unsigned build_threads = 1;  // --build-threads: the wide BVH rows' build threads
    bool build_table = true;     // --no-build-table: skip the 1- and 2-thread build timing
    bool quantized = false;      // --quantized: with --wide --few, also bvh8 with quantized boxes
    bool sbvh = false;           // --sbvh: also bvh8 with spatial splits (tree sbvh8)
    bool compact = false;        // --compact-subtrees: also the wide BVH in compact subtrees
    bool quick = false, no_generated = false, all = false, memory = false, few = false, wide = false, big = false;
    // --bvh-ct, --bvh-ci, --bvh-block, --bvh-leaf: the wide BVH's SAH. Tree bvh8 without spatial
    // splits (the binned tree), sbvh8 with them at every node (--sbvh-alpha, --sbvh-budget).
    BvhBuildOptions bvh = [] {
        BvhBuildOptions o = BvhBuildOptions::full_spatial_splits();
        o.spatial_splits = false;
        return o;
    }();
    std::size_t rays = 1'000'000;
    int reps = 3;
    KdBuildOptions kd{};  // --ki, --empty-bonus: the kd-tree's SAH constants (K_T = 1)
    bool user_meshes = false;  // --user-meshes: support/user_meshes.hpp's mode
    std::string scenes_dir = GLINT_BENCH_SCENES;  // --scenes DIR
    int primary = 384;                            // --primary N: N x N primary rays (--user-meshes)
    std::optional<Isa> isa;                       // --isa NAME: glint's kernels (--user-meshes)
    int builds = 3;                               // --builds N: alternating builds per mesh (--user-meshes)
    bool rays_set = false, reps_set = false;
};

struct Row {
    std::string scene, rays, tree, layout, intersector;
    double mrays = 0, build_s = 0, embree = 0;
    std::size_t node_bytes = 0;
    double bytes_per_tri = 0;
    double agree = 0;  // fraction of rays whose hit/miss and t agree with Embree
    double ratio = 0;  // median over passes of (Embree time / our time), passes adjacent in time
    unsigned build_threads = 1;
};

/// Traces every ray set of the scene with one accelerator; returns one row per set. The
/// peer (Embree), when there is one, is timed on the same rays alternately with ours, so
/// that both see the same machine load; each keeps its best of --reps passes. `base` holds
/// the row's names, build time and memory.
template <class Accel>
void time_sets(const Scene& sc, const Accel& acc, const Peer* peer, const Options& opt, const Row& base,
               std::vector<Row>& rows) {
    std::vector<float> peer_t;
    for (std::size_t s = 0; s < sc.sets.size(); ++s) {
        const auto& rays = sc.sets[s].rays;
        double best = infinity<double>, peer_best = infinity<double>;
        std::vector<double> ratios;  // per pass: peer time / our time, adjacent in time
        std::size_t agree = 0;
        if (!opt.solo.empty()) {  // one tracer alone, for profilers: no timing, no pairing
            std::size_t hits = 0;
            for (int rep = 0; rep < opt.reps; ++rep) {
                if (opt.solo == "embree" && peer) peer->trace(rays, peer_t);
                if (opt.solo == "glint")
                    for (const auto& r : rays) {
                        StoreHit<float> h;
                        hits += acc.closest_hit(r, h);
                    }
            }
            std::printf("# solo %s: %s/%s, %d passes, %zu hits\n", opt.solo.c_str(), sc.name.c_str(),
                        sc.sets[s].name.c_str(), opt.reps, hits);
            continue;
        }
        for (int rep = 0; rep < opt.reps; ++rep) {
            const double ours = closest_hit_pass(acc, rays);
            best = std::min(best, ours);
            if (peer) {
                const double t2 = pass_clock();
                peer->trace(rays, peer_t);
                const double theirs = pass_clock() - t2;
                peer_best = std::min(peer_best, theirs);
                ratios.push_back(theirs / ours);
            }
        }
        std::sort(ratios.begin(), ratios.end());
        if (peer) {
            for (std::size_t i = 0; i < rays.size(); ++i) {
                StoreHit<float> h;
                acc.closest_hit(rays[i], h);
                const float te = peer_t[i];
                agree += (std::isinf(te) && std::isinf(h.t)) || std::abs(te - h.t) <= 1e-3f * std::max(1.f, te);
            }
        }
        WideBvhCounters counted;
        if constexpr (requires { acc.closest_hit(rays[0], std::declval<StoreHit<float>&>(), counted); }) {
            for (const auto& r : rays) {
                StoreHit<float> h;
                acc.closest_hit(r, h, counted);
            }
        }
        Row row = base;
        row.rays = sc.sets[s].name;
        row.mrays = double(rays.size()) / best * 1e-6;
        row.embree = peer ? double(rays.size()) / peer_best * 1e-6 : 0.0;
        row.agree = peer ? double(agree) / double(rays.size()) : -1.0;
        row.ratio = ratios.empty() ? 0.0 : ratios[ratios.size() / 2];
        std::printf("%-12s %-10s %-4s %-11s %-14s %8.3f Mrays/s  build %7.3f s  nodes %10zu B (%6.1f B/tri)", row.scene.c_str(),
                    row.rays.c_str(), row.tree.c_str(), row.layout.c_str(), row.intersector.c_str(), row.mrays, row.build_s,
                    row.node_bytes, row.bytes_per_tri);
        if (row.embree > 0) std::printf("  x%.3f of Embree  agree %.4f", row.ratio, row.agree);
        if (counted.nodes)
            std::printf("  per ray: %.1f nodes %.1f leaves %.1f records", double(counted.nodes) / double(rays.size()),
                        double(counted.leaves) / double(rays.size()), double(counted.records) / double(rays.size()));
        std::printf("\n");
        std::fflush(stdout);
        rows.push_back(row);
    }
}

/// A builder's tree and the wall time its build took.
struct TimedTree {
    BuiltTree<float> tree;
    double seconds = 0;
};

template <class Builder>
TimedTree timed_build(const Builder& builder, const Mesh<float>& mesh) {
    const auto t0 = Clock::now();
    BuiltTree<float> tree = builder.build(mesh);
    return {std::move(tree), seconds_since(t0)};
}

/// One kd-tree or BIH combination, encoded from the scene's built tree; its build time is
/// the builder's plus the encoding's.
template <class Accel>
void run_combination(const Scene& sc, const TimedTree& built, const Peer* peer, const Options& opt,
                     std::vector<Row>& rows) {
    const auto t0 = Clock::now();
    const Accel acc(sc.mesh, built.tree);
    Row base;
    base.scene = sc.name;
    base.tree = built.tree.kind == TreeKind::kd ? "kd" : "bih";
    base.layout = layout_label(std::type_identity<typename Accel::layout_type>{});
    base.intersector = bench::intersector_name<typename Accel::intersector_type>;
    base.build_s = built.seconds + seconds_since(t0);
    base.node_bytes = acc.stats().node_bytes();
    base.bytes_per_tri = acc.stats().bytes_per_triangle();
    time_sets(sc, acc, peer, opt, base, rows);
}

/// The wide BVH over intersector P, N wide, child boxes as B, nodes arranged by L, built on
/// --build-threads threads;
/// with `spatial`, with spatial splits (tree sbvh8 / sbvh4), whose references it prints.
template <class P, int N, WideBoxes B = WideBoxes::floats, WideNodeLayout L = WideBuildOrder>
void run_wide(const Scene& sc, const Peer* peer, const Options& opt, std::vector<Row>& rows, bool spatial = false) {
    BvhBuildOptions bo = opt.bvh;
    bo.threads = opt.build_threads;
    bo.spatial_splits = spatial;
    const auto t0 = Clock::now();
    const MeshBvh<P, N, B, L> acc(sc.mesh, bo);
    const double build_s = seconds_since(t0);
    Row base;
    base.scene = sc.name;
    base.tree = std::string(spatial ? "sbvh" : "bvh") + std::to_string(N);
    if (spatial)
        std::printf("# %s %s: %zu references for %zu triangles (x%.3f, budget x%.2f), build %.4f s on %u thread(s)\n",
                    sc.name.c_str(), base.tree.c_str(), acc.bvh().prims().size(), sc.mesh.size(),
                    double(acc.bvh().prims().size()) / double(sc.mesh.size()), double(bo.spatial_budget),
                    build_s, bo.threads);
    base.layout = wide_layout_label<B>(std::type_identity<L>{});
    base.intersector = bench::intersector_name<P>;
    base.build_s = build_s;
    base.node_bytes = acc.bvh().stats().node_bytes;
    base.bytes_per_tri = double(base.node_bytes) / double(sc.mesh.size());
    base.build_threads = bo.threads;
    time_sets(sc, acc, peer, opt, base, rows);
}

/// --sbvh: the 8-wide BVH without and with spatial splits (Moller-Trumbore) timed against
/// each other directly, passes alternating (which goes first alternates too), per set the
/// median over --reps pairs of (time without / time with): above 1, spatial splits are faster.
void compare_spatial(const Scene& sc, const Options& opt) {
    BvhBuildOptions bo = opt.bvh;
    bo.threads = opt.build_threads;
    auto build_start = Clock::now();
    const MeshBvh<MollerTrumbore<float>, 8> plain(sc.mesh, bo);
    const double plain_s = seconds_since(build_start);
    bo.spatial_splits = true;
    build_start = Clock::now();
    const MeshBvh<MollerTrumbore<float>, 8> split(sc.mesh, bo);
    const double split_s = seconds_since(build_start);
    for (const auto& set : sc.sets) {
        std::vector<double> ratios;
        for (int rep = 0; rep < opt.reps; ++rep) {
            double without = 0, with = 0;
            if (rep % 2 == 0) {
                without = closest_hit_pass(plain, set.rays);
                with = closest_hit_pass(split, set.rays);
            } else {
                with = closest_hit_pass(split, set.rays);
                without = closest_hit_pass(plain, set.rays);
            }
            ratios.push_back(without / with);
        }
        std::sort(ratios.begin(), ratios.end());
        std::printf("# %s %s: sbvh8 / bvh8 speed x%.3f (median of %d paired passes, range %.3f ... %.3f); build %.4f / %.4f s "
                    "(x%.1f), references x%.3f\n",
                    sc.name.c_str(), set.name.c_str(), ratios[ratios.size() / 2], opt.reps, ratios.front(), ratios.back(),
                    split_s, plain_s, split_s / plain_s,
                    double(split.bvh().prims().size()) / double(sc.mesh.size()));
        std::fflush(stdout);
    }
}

/// CPU seconds used so far by this process (who = RUSAGE_SELF) or this thread (RUSAGE_THREAD).
double cpu_seconds(int who) {
    rusage u{};
    getrusage(who, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Build time of the 8-wide BVH (Moller-Trumbore records) on 1 and 2 threads, median of 7
/// alternating builds each, and its memory next to Embree's. On a loaded machine the wall
/// time of the 2-thread build says little (no core is free), so it also prints CPU time:
/// the 1-thread build's, and the 2-thread build's split into the calling thread's and the
/// others'; the larger part bounds the 2-thread wall time on an idle machine from below.
void wide_build_table(const Scene& sc, const Peer* peer, const Options& opt) {
    std::vector<double> t1, t2, cpu1, main2, other2;
    std::size_t total = 0, nodes = 0;
    for (int rep = 0; rep < 7; ++rep)
        for (unsigned threads : {1u, 2u}) {
            BvhBuildOptions bo = opt.bvh;
            bo.threads = threads;
            const double p0 = cpu_seconds(RUSAGE_SELF), m0 = cpu_seconds(RUSAGE_THREAD);
            const auto w0 = Clock::now();
            const MeshBvh<MollerTrumbore<float>, 8> acc(sc.mesh, bo);
            const double wall = seconds_since(w0);
            const double p = cpu_seconds(RUSAGE_SELF) - p0, m = cpu_seconds(RUSAGE_THREAD) - m0;
            (threads == 1 ? t1 : t2).push_back(wall);
            if (threads == 1) cpu1.push_back(p);
            else main2.push_back(m), other2.push_back(p - m);
            total = acc.total_bytes();
            nodes = acc.bvh().stats().node_bytes;
        }
    for (auto* v : {&t1, &t2, &cpu1, &main2, &other2}) std::sort(v->begin(), v->end());
    const double n = double(sc.mesh.size());
    std::printf("# %s bvh8 build: 1 thread %.4f s, 2 threads %.4f s (x%.2f); CPU: 1 thread %.4f s, 2 threads "
                "%.4f + %.4f s (x%.2f); %.1f B/tri (nodes %.1f, records %.1f)",
                sc.name.c_str(), t1[3], t2[3], t1[3] / t2[3], cpu1[3], main2[3], other2[3],
                cpu1[3] / std::max(main2[3], other2[3]), double(total) / n, double(nodes) / n, double(total - nodes) / n);
#ifdef GLINT_HAVE_EMBREE
    if (peer)
        std::printf("; Embree threads=1 build %.4f s (bvh8 1 thread / Embree x%.2f), %.1f B/tri", peer->build_seconds,
                    t1[3] / peer->build_seconds, double(peer->bytes) / n);
#else
    (void)peer;
#endif
    std::printf("\n");
}

template <class P, class... Layouts>
void run_layouts(const Scene& sc, const TimedTree& kd, const TimedTree& bih, const Peer* peer,
                 const Options& opt, std::vector<Row>& rows) {
    (run_combination<KdTree<float, P, Layouts>>(sc, kd, peer, opt, rows), ...);
    (run_combination<Bih<float, P, Layouts>>(sc, bih, peer, opt, rows), ...);
}

template <class P>
void run_intersector(const Scene& sc, const TimedTree& kd, const TimedTree& bih, const Peer* peer,
                     const Options& opt, std::vector<Row>& rows) {
    if (opt.quick || opt.few) {
        run_layouts<P, PointerLayout, CompactSubtrees<31>>(sc, kd, bih, peer, opt, rows);
    } else if (opt.all) {
        run_layouts<P, PointerLayout, HavranSubtrees<3>, CompactSubtrees<3>, HavranSubtrees<7>, CompactSubtrees<7>,
                    HavranSubtrees<15>, CompactSubtrees<15>, HavranSubtrees<31>, CompactSubtrees<31>,
                    HavranSubtrees<63>, CompactSubtrees<63>>(sc, kd, bih, peer, opt, rows);
    } else {
        run_layouts<P, PointerLayout, HavranSubtrees<7>, CompactSubtrees<7>, HavranSubtrees<31>, CompactSubtrees<31>>(
            sc, kd, bih, peer, opt, rows);
    }
}

/// Node memory of one layout for a built tree (leaf contents do not matter here).
template <class L>
LayoutStats layout_stats(const BuiltTree<float>& t) {
    std::vector<std::array<std::uint32_t, 2>> groups(t.nodes.size(), {0u, 1u});
    std::vector<KdNode<float>> kd;
    std::vector<BihNode<float>> bih;
    return t.kind == TreeKind::kd ? L::encode(t, std::span<const std::array<std::uint32_t, 2>>(groups), kd)
                                  : L::encode(t, std::span<const std::array<std::uint32_t, 2>>(groups), bih);
}

template <std::uint32_t K>
void memory_row(const std::string& scene, const char* tree, const BuiltTree<float>& t, const LayoutStats& p) {
    const LayoutStats h = layout_stats<HavranSubtrees<K>>(t), c = layout_stats<CompactSubtrees<K>>(t);
    std::printf("| %-10s | %-4s | %2u | %10zu | %10zu | %10zu | %5.1f%% | %8.1f | %8.1f | %8.1f |\n", scene.c_str(), tree, K,
                p.node_bytes(), h.node_bytes(), c.node_bytes(), 100.0 * (1.0 - double(c.node_bytes()) / double(h.node_bytes())),
                p.bytes_per_triangle(), h.bytes_per_triangle(), c.bytes_per_triangle());
}

/// --memory: node bytes of pointer, havran-K and compact-K for K = 3 ... 63 (Szécsi 2009, Fig. 4.6).
void memory_table(const std::vector<std::pair<std::string, Mesh<float>>>& scenes) {
    std::puts("| scene      | tree |  K | pointer B  | havran-K B | compact-K B | saving | ptr B/tri | hav B/tri | cmp B/tri |");
    std::puts("|------------|------|----|------------|------------|------------|--------|----------|----------|----------|");
    for (const auto& [name, mesh] : scenes) {
        for (const BuiltTree<float>& t : {KdTreeBuilder<float>{}.build(mesh), BihBuilder<float>{}.build(mesh)}) {
            const char* tree = t.kind == TreeKind::kd ? "kd" : "bih";
            const LayoutStats p = layout_stats<PointerLayout>(t);
            memory_row<3>(name, tree, t, p);
            memory_row<7>(name, tree, t, p);
            memory_row<15>(name, tree, t, p);
            memory_row<31>(name, tree, t, p);
            memory_row<63>(name, tree, t, p);
        }
    }
}

/// The flags that choose what is timed.
void add_run_flags(cli::App& app, Options& o) {
    cli::texts(app, "--mesh", o.meshes, "an OBJ mesh to time besides the generated scenes (repeatable)")->group("Run");
    cli::output(app, "--csv", o.csv, "write the rows as CSV")->group("Run");
    cli::flag(app, "--quick", o.quick, "a smoke run: at most 20000 rays, one repetition")->group("Run");
    cli::number_to<std::size_t>(app, "--rays", [&o](std::size_t n) { o.rays = n, o.rays_set = true; }, 1, std::size_t(1) << 40,
                                "rays per set (default 1000000; --user-meshes: 200000)")->group("Run");
    cli::number_to<int>(app, "--reps", [&o](int n) { o.reps = n, o.reps_set = true; }, 1, 1000,
                        "timed repetitions (default 3; --user-meshes: 5)")->group("Run");
    cli::flag(app, "--no-generated", o.no_generated, "leave out the generated scenes")->group("Run");
    cli::text(app, "--only", o.only, "time only this scene", "SCENE")->group("Run");
    cli::flag(app, "--all", o.all, "every tree, layout and intersector")->group("Run");
    cli::flag(app, "--few", o.few, "the main rows only")->group("Run");
    cli::flag(app, "--memory", o.memory, "node memory of each layout")->group("Run");
    cli::flag(app, "--wide", o.wide, "the wide BVH rows")->group("Run");
    cli::flag(app, "--cpu-time", use_cpu_time, "time by the process's CPU clock instead of the wall clock")->group("Run");
    cli::text(app, "--set", o.set, "one ray set only: primary or incoherent", "SET")->group("Run");
    cli::flag(app, "--big", o.big, "the big generated scenes too")->group("Run");
    cli::text(app, "--solo", o.solo, "trace with glint or embree alone, untimed (for profilers)", "NAME")->group("Run");
    app.flag("--no-build-table", [&o] { o.build_table = false; }, "skip the 1- and 2-thread build timing")->group("Run");
    cli::flag(app, "--quantized", o.quantized, "with --wide --few, also bvh8 with quantized boxes")->group("Run");
    cli::flag(app, "--sbvh", o.sbvh, "also bvh8 with spatial splits (tree sbvh8)")->group("Run");
    cli::flag(app, "--compact-subtrees", o.compact, "also the wide BVH in compact subtrees")->group("Run");
    cli::flag(app, "--user-meshes", o.user_meshes, "every mesh of --scenes through MeshBvh's public API against Embree")
        ->group("Run");
    cli::text(app, "--scenes", o.scenes_dir, "--user-meshes: the folder of OBJ meshes", "DIR")->group("Run");
    cli::number(app, "--primary", o.primary, 1, 8192, "--user-meshes: N x N primary rays")->group("Run");
    const auto set_isa = [&o](const std::string& name) { return bench::parse_isa(name, o.isa); };
    app.value("--isa", set_isa, "--user-meshes: glint's kernels (default: the best this CPU runs)", "NAME",
              isa_name(best_isa()))
        ->group("Run");
    cli::number(app, "--builds", o.builds, 1, 1000, "--user-meshes: alternating builds per mesh (median; default 3)")
        ->group("Run");
}

/// The trees' build settings.
void add_build_flags(cli::App& app, Options& o) {
    cli::number(app, "--build-threads", o.build_threads, 1u, 1024u, "the wide BVH rows' build threads")->group("Build");
    cli::number(app, "--sbvh-alpha", o.bvh.spatial_alpha, 0.0f, 1.0f, "spatial splits: overlap threshold alpha")->group("Build");
    cli::number(app, "--sbvh-budget", o.bvh.spatial_budget, 1.0f, 4.0f, "spatial splits: references per primitive at most")->group("Build");
    cli::number_to<int>(app, "--bvh-siblings", [&o](int k) {
        o.bvh.node_order = k ? WideNodeOrder::sibling_blocks : WideNodeOrder::depth_first;
    }, 0, 1, "1: sibling blocks node order (default 0: depth first)")->group("Build");
    cli::number(app, "--bvh-ct", o.bvh.traversal_cost, 0.0f, 1e6f, "SAH traversal cost C_T")->group("Build");
    cli::number(app, "--bvh-ci", o.bvh.intersection_cost, 0.0f, 1e6f, "SAH intersection cost C_I")->group("Build");
    cli::number(app, "--bvh-cn", o.bvh.wide_node_cost, 0.0f, 1e6f, "collapse: cost of a wide node C_N")->group("Build");
    cli::number(app, "--bvh-block", o.bvh.leaf_block, 1u, 64u, "triangles per leaf block")->group("Build");
    cli::number(app, "--bvh-leaf", o.bvh.max_leaf, 1u, 16u, "largest leaf")->group("Build");
    cli::number(app, "--bvh-bins", o.bvh.bins, 2u, 64u, "SAH centre bins per axis")->group("Build");
    cli::number(app, "--ki", o.kd.intersection_cost, 1e-6, 1e6, "kd-tree SAH intersection cost K_I (K_T = 1)")->group("Build");
    cli::number(app, "--empty-bonus", o.kd.empty_bonus, 0.0, 0.999, "kd-tree SAH empty-space bonus")->group("Build");
}

Options parse(int argc, char** argv) {
    Options o;
    cli::App app("bench_trees: the trees' ray throughput and build time against Embree 3, single thread");
    add_run_flags(app, o);
    add_build_flags(app, o);
    cli::parse_or_exit(app, argc, argv, "bench_trees");
    if (o.quick) {
        o.rays = std::min<std::size_t>(o.rays, 20'000);
        o.reps = 1;
    }
    return o;
}

/// --user-meshes: every mesh of --scenes through MeshBvh's public calls against Embree HIGH and
/// MEDIUM (support/user_meshes.hpp); --csv rows carry api, embree_quality and query.
int user_meshes_main(const Options& opt) {
#ifdef GLINT_HAVE_EMBREE
    bench::UserMeshOptions u;
    u.scenes = opt.scenes_dir;
    u.only = opt.only;
    u.generated = !opt.no_generated;
    u.primary = opt.primary;
    u.isa = opt.isa;
    u.builds = opt.builds;
    u.rays = opt.rays_set ? opt.rays : 200'000;
    u.reps = opt.reps_set ? opt.reps : 5;
    bench::PassClock::thread_cpu = use_cpu_time;  // --cpu-time times the passes here too
    const auto rows = bench::run_user_meshes(u, [](const std::string& f) { return bench::read_obj(f); });
    if (!opt.csv.empty()) bench::write_user_csv(opt.csv, rows);
    return 0;
#else
    (void)opt;
    throw Error("--user-meshes needs Embree 3 (not found at configure time)");
#endif
}

}  // namespace

int main(int argc, char** argv) try {
    const Options opt = parse(argc, argv);
    if (opt.user_meshes) return user_meshes_main(opt);
    std::vector<Scene> scenes;
    if (!opt.no_generated) {
        scenes.push_back({"torus-knot", make_torus_knot<float>(), {}});
        if (!opt.quick) {
            scenes.push_back({"stadium", make_teapot_in_stadium<float>(), {}});
            scenes.push_back({"knot-128k", make_torus_knot<float>(2000, 32), {}});
        }
        if (opt.big) scenes.push_back({"knot-2m", make_torus_knot<float>(16000, 64), {}});
    }
    for (const auto& path : opt.meshes) {
        std::string name = path.substr(path.find_last_of('/') + 1);
        name = name.substr(0, name.find_last_of('.'));
        scenes.push_back({name, bench::read_obj(path), {}});
    }
    if (!opt.only.empty())
        std::erase_if(scenes, [&](const Scene& sc) { return sc.name != opt.only; });
    if (opt.memory) {
        std::vector<std::pair<std::string, Mesh<float>>> meshes;
        for (const Scene& sc : scenes) meshes.emplace_back(sc.name, sc.mesh);
        memory_table(meshes);
        return 0;
    }
    std::vector<Row> rows;
    for (Scene& sc : scenes) {
        const int width = 1024, height = std::max<int>(1, int(opt.rays / width));
        if (opt.set.empty() || opt.set == "primary")
            sc.sets.push_back({"primary", make_primary_rays<float>(sc.mesh, width, height)});
        if (opt.set.empty() || opt.set == "incoherent")
            sc.sets.push_back({"incoherent", make_incoherent_rays<float>(sc.mesh, opt.rays)});
        if (sc.sets.empty()) throw Error("--set " + opt.set + ": no such ray set");
        std::printf("# scene %s: %zu triangles, %zu %s rays%s\n", sc.name.c_str(), sc.mesh.size(), sc.sets[0].rays.size(),
                    sc.sets[0].name.c_str(),
                    sc.sets.size() > 1 ? (", " + std::to_string(sc.sets[1].rays.size()) + " incoherent rays").c_str() : "");
        std::unique_ptr<Peer> peer;
#ifdef GLINT_HAVE_EMBREE
        peer = std::make_unique<Peer>(sc.mesh);
        std::printf("# Embree %d.%d.%d build %.3f s (threads=1), timed alternately with each combination\n",
                    RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH, peer->build_seconds);
#else
        std::puts("# Embree 3 not found: no peer comparison");
#endif
        if (!opt.solo.empty()) {
            run_wide<MollerTrumbore<float>, 8>(sc, peer.get(), opt, rows);
            continue;
        }
        if (opt.build_table) wide_build_table(sc, peer.get(), opt);
        run_wide<MollerTrumbore<float>, 8>(sc, peer.get(), opt, rows);
        if (opt.sbvh) {
            run_wide<MollerTrumbore<float>, 8>(sc, peer.get(), opt, rows, true);
            compare_spatial(sc, opt);
        }
        if (!opt.wide || !opt.few || opt.quantized) run_wide<MollerTrumbore<float>, 8, WideBoxes::quantized>(sc, peer.get(), opt, rows);
        if (!opt.wide || !opt.few) run_wide<Wald<float>, 8>(sc, peer.get(), opt, rows);
        if (opt.compact) {  // Szécsi 2009's compact subtrees against the collapse's order, 8 and 4 wide (4 KiB units)
            run_wide<MollerTrumbore<float>, 8, WideBoxes::floats, WideCompactSubtrees<18>>(sc, peer.get(), opt, rows);
            run_wide<MollerTrumbore<float>, 4>(sc, peer.get(), opt, rows);
            run_wide<MollerTrumbore<float>, 4, WideBoxes::floats, WideCompactSubtrees<36>>(sc, peer.get(), opt, rows);
        }
        if (!opt.quick && !opt.few) {
            run_wide<MollerTrumbore<float>, 4>(sc, peer.get(), opt, rows);
            run_wide<Watertight<float>, 8>(sc, peer.get(), opt, rows);
            run_wide<Ivm<float>, 8>(sc, peer.get(), opt, rows);
        }
        if (!opt.wide) {
            const TimedTree kd = timed_build(KdTreeBuilder<float>{opt.kd}, sc.mesh);
            const TimedTree bih = timed_build(BihBuilder<float>{}, sc.mesh);
            run_intersector<Ivm<float>>(sc, kd, bih, peer.get(), opt, rows);
            run_intersector<MollerTrumbore<float>>(sc, kd, bih, peer.get(), opt, rows);
            run_intersector<Wald<float>>(sc, kd, bih, peer.get(), opt, rows);
            run_intersector<Watertight<float>>(sc, kd, bih, peer.get(), opt, rows);
        }
        for (std::size_t s = 0; s < sc.sets.size(); ++s) {
            const Row* best = nullptr;
            for (const Row& r : rows)
                if (r.scene == sc.name && r.rays == sc.sets[s].name &&
                    (!best || (r.embree > 0 ? r.ratio > best->ratio : r.mrays > best->mrays)))
                    best = &r;
            if (best)
                std::printf("# best on %s/%s: %s %s %s %.3f Mrays/s%s\n", sc.name.c_str(), best->rays.c_str(),
                            best->tree.c_str(), best->layout.c_str(), best->intersector.c_str(), best->mrays,
                            best->embree > 0 ? (", " + std::to_string(best->ratio) + " x Embree").c_str() : "");
        }
    }
    if (!opt.csv.empty()) {
        std::ofstream out(opt.csv);
        if (!out) throw Error("cannot write '" + opt.csv + "'");
        out << "scene,rays,tree,layout,intersector,mrays_per_s,build_s,node_bytes,bytes_per_triangle,embree_mrays_per_s,"
               "build_threads,api,embree_quality,query\n";
        for (const Row& r : rows) {
            out << r.scene << ',' << r.rays << ',' << r.tree << ',' << r.layout << ',' << r.intersector << ',' << r.mrays
                << ',' << r.build_s << ',' << r.node_bytes << ',' << r.bytes_per_tri << ',';
            if (r.embree > 0) out << r.embree;
            out << ',' << r.build_threads << ",internal,medium,closest_hit\n";
        }
        std::printf("# wrote %s (%zu rows)\n", opt.csv.c_str(), rows.size());
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_trees: %s\n", e.what());
    return 1;
}
