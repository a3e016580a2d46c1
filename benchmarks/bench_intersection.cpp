// bench_intersection: time per ray-triangle test for every policy, scalar and batch, float
// and double, on a realistic hit/miss mix (about 22% hits: each ray aims at a point of its
// triangle's plane with barycentrics in [-0.25, 1.25]^2), then a table of ratios to
// Moller-Trumbore measured in the same run.
//
//   ./build/benchmarks/bench_intersection                      # all, median of 5 repetitions
//   ./build/benchmarks/bench_intersection --benchmark_filter=Ivm
//
// Scalar: one record against its own ray, records in the SoA store's frame (the ray data is
// prepared beforehand, as a tree does once per leaf), 4096 pairs. Batch: each ray against a
// block of 8 records with the vectorized kernel (TriangleStore::closest_hit).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/wald.hpp>
#include <glint/intersection/watertight.hpp>

#include "../tests/intersection_cases.hpp"
#include "support/intersector_names.hpp"

using namespace glint;

namespace {

constexpr std::size_t kPairs = 4096;
constexpr std::size_t kBlock = 8;

template <class P>
struct ScalarSetup {
    using T = typename P::scalar_type;
    std::vector<P> records;
    std::vector<RayDataOf<P>> rays;
    ScalarSetup() {
        const auto cases = testing::random_cases<T>(42, kPairs);
        for (const auto& c : cases) {
            // Each pair in its own store group, as a leaf would hold it (IVM: frame chosen).
            TriangleStore<P> store;
            const std::uint32_t id = 0;
            store.add_block(std::span(&c.tri, 1), std::span(&id, 1));
            records.push_back(store.record(0));
            rays.push_back(P::prepare(TriangleStore<P>::Frame::local(c.ray, store.group(0).origin)));
        }
    }
};

template <class P>
void scalar(benchmark::State& state) {
    static const ScalarSetup<P> s;
    std::size_t hits = 0;
    for (auto _ : state) {
        for (std::size_t i = 0; i < kPairs; ++i) {
            TriangleHit<typename P::scalar_type> h;
            const bool hit = intersect_record(s.records[i], s.rays[i], h);
            benchmark::DoNotOptimize(hit);  // keeps the loop one test at a time
            hits += hit;
        }
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kPairs));
    state.counters["hit_rate"] = double(hits) / double(state.iterations() * kPairs);
}

template <class P>
struct BatchSetup {
    using T = typename P::scalar_type;
    TriangleStore<P> store;
    std::vector<typename TriangleStore<P>::BlockRef> blocks;
    std::vector<Ray<T>> rays;
    BatchSetup() {
        const auto cases = testing::random_cases<T>(42, kPairs);
        for (std::size_t b = 0; b < kPairs / kBlock; ++b) {
            std::vector<TriangleVertices<T>> tris;
            std::vector<std::uint32_t> ids;
            for (std::size_t k = 0; k < kBlock; ++k) {
                tris.push_back(cases[b * kBlock + k].tri);
                ids.push_back(static_cast<std::uint32_t>(b * kBlock + k));
            }
            blocks.push_back(store.add_block(tris, ids));
        }
        for (const auto& c : cases) rays.push_back(c.ray);
    }
};

template <class P>
void batch(benchmark::State& state) {
    static const BatchSetup<P> s;
    std::size_t hits = 0;
    for (auto _ : state) {
        for (std::size_t i = 0; i < kPairs; ++i) {
            StoreHit<typename P::scalar_type> h;
            hits += s.store.closest_hit(s.blocks[i / kBlock], s.rays[i], h);
        }
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kPairs * kBlock));
    state.counters["ray_hit_rate"] = double(hits) / double(state.iterations() * kPairs);
}

template <class P>
std::string bench_name(const char* kind) {
    std::string n = std::string(kind) + "/" + bench::intersector_name<P>;
    if (sizeof(typename P::scalar_type) == 8) n += "/Double";
    return n;
}

template <class P>
void register_policy() {
    benchmark::RegisterBenchmark(bench_name<P>("Scalar").c_str(), scalar<P>);
    benchmark::RegisterBenchmark(bench_name<P>("Batch").c_str(), batch<P>);
}

/// Collects the median ns per test of each benchmark for the ratio table.
class Collector : public benchmark::ConsoleReporter {
public:
    std::map<std::string, double> ns_per_test;
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& r : runs) {
            const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
            const bool single = r.run_type == Run::RT_Iteration && r.repetitions <= 1;
            if (!median && !single) continue;
            const auto it = r.counters.find("items_per_second");
            if (it != r.counters.end() && it->second.value > 0)
                ns_per_test[r.run_name.function_name] = 1e9 / it->second.value;
        }
    }
};

}  // namespace

int main(int argc, char** argv) {
    register_policy<Ivm<float>>();
    register_policy<MollerTrumbore<float>>();
    register_policy<Wald<float>>();
    register_policy<Watertight<float>>();
    register_policy<Ivm<double>>();
    register_policy<MollerTrumbore<double>>();
    register_policy<Wald<double>>();
    register_policy<Watertight<double>>();

    // Median of 5 repetitions unless the command line says otherwise: the machines are
    // shared and noisy, and only ratios within one run are meaningful.
    std::vector<char*> args(argv, argv + argc);
    std::string reps = "--benchmark_repetitions=5", agg = "--benchmark_report_aggregates_only=true";
    bool has_reps = false;
    for (int i = 1; i < argc; ++i) has_reps |= std::string(argv[i]).rfind("--benchmark_repetitions", 0) == 0;
    if (!has_reps) {
        args.push_back(reps.data());
        args.push_back(agg.data());
    }
    int n = static_cast<int>(args.size());
    benchmark::Initialize(&n, args.data());
    if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
    Collector collector;
    benchmark::RunSpecifiedBenchmarks(&collector);
    benchmark::Shutdown();

    std::printf("\nns per ray-triangle test (median), and ratio to Moller-Trumbore of the same kind:\n");
    std::printf("%-34s %10s %12s\n", "benchmark", "ns/test", "vs MT");
    for (const auto& [name, ns] : collector.ns_per_test) {
        std::string base = name;
        for (const char* p : {"Ivm", "Wald", "Watertight"}) {
            const auto pos = base.find(p);
            if (pos != std::string::npos) base.replace(pos, std::string(p).size(), "MollerTrumbore");
        }
        const auto b = collector.ns_per_test.find(base);
        if (b != collector.ns_per_test.end())
            std::printf("%-34s %10.3f %12.3f\n", name.c_str(), ns, ns / b->second);
        else
            std::printf("%-34s %10.3f %12s\n", name.c_str(), ns, "-");
    }
    const auto ivm = collector.ns_per_test.find("Scalar/Ivm"), mt = collector.ns_per_test.find("Scalar/MollerTrumbore");
    if (ivm != collector.ns_per_test.end() && mt != collector.ns_per_test.end())
        std::printf("\nIVM / Moller-Trumbore time per scalar float test: %.3f (Szécsi 2009, §4.1.1 claims < 1)\n",
                    ivm->second / mt->second);
    return 0;
}
