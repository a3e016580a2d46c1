// stress_intersection: the numerical-stability report of the four ray-triangle tests.
//
// For each policy (float and double) and stress category, the false-miss and false-hit
// rates against the extended-precision reference (glint/intersection/reference.hpp), the
// number of wrong decisions farther than 16 "edge ulps" from any edge (a real error, not
// rounding at the boundary), and the largest error in t. The closed-mesh category shoots
// rays exactly at the shared edges and vertices of a closed icosphere, where every ray must
// hit something: its false-miss rate is the leak rate.
//
//   ./build/benchmarks/stress_intersection [--csv FILE] [--quick]
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/wald.hpp>
#include <glint/intersection/watertight.hpp>

#include "../tests/intersection_cases.hpp"
#include "support/intersector_names.hpp"

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;
using namespace glint::testing;

namespace {

constexpr double kBand = 16.0;

struct Row {
    std::string policy, precision, category;
    std::size_t cases = 0, reference_hits = 0, false_miss = 0, false_hit = 0, far_errors = 0;
    double max_t_ulps = 0;
};

template <class P>
void run_policy(std::vector<Row>& rows, std::size_t scale) {
    using T = typename P::scalar_type;
    const std::string prec = sizeof(T) == 4 ? "float" : "double";
    auto add = [&](const std::string& category, const std::vector<Case<T>>& cases) {
        const Agreement a = measure_agreement<P>(cases, kBand);
        rows.push_back({bench::intersector_name<P>, prec, category, a.pairs, a.reference_hits, a.false_miss, a.false_hit,
                        a.false_miss_far + a.false_hit_far, a.max_t_ulps});
    };
    add("random", random_cases<T>(2024, 100 * scale));
    add("sliver", sliver_cases<T>(7, 50 * scale));
    add("far-1e3", random_cases<T>(99, 20 * scale, T(1e3)));
    add("far-1e6", random_cases<T>(99, 20 * scale, T(1e6)));
    add("origin-plane", origin_plane_cases<T>(5, 50 * scale));
    add("zero-area", zero_area_cases<T>(13, 10 * scale));
    add("parallel", parallel_cases<T>(17, 10 * scale));
    add("nonfinite", nonfinite_cases<T>());

    std::size_t rays_total = 0;
    const std::size_t leaks_total = closed_mesh_leaks<P>(rays_total);
    rows.push_back({bench::intersector_name<P>, prec, "closed-mesh", rays_total, rays_total, leaks_total, 0, leaks_total, 0});
}

}  // namespace

int main(int argc, char** argv) {
    std::string csv;
    std::size_t scale = 1000;
    cli::App app("stress_intersection: the triangle tests on near-degenerate, grazing and edge-crossing rays against "
                 "exact arithmetic");
    cli::output(app, "--csv", csv, "write the rows as CSV");
    app.flag("--quick", [&scale] { scale = 100; }, "a smoke run: a tenth of the rays");
    cli::parse_or_exit(app, argc, argv, "stress_intersection");
    std::vector<Row> rows;
    run_policy<Ivm<float>>(rows, scale);
    run_policy<MollerTrumbore<float>>(rows, scale);
    run_policy<Wald<float>>(rows, scale);
    run_policy<Watertight<float>>(rows, scale);
    run_policy<Ivm<double>>(rows, scale);
    run_policy<MollerTrumbore<double>>(rows, scale);
    run_policy<Wald<double>>(rows, scale);
    run_policy<Watertight<double>>(rows, scale);

    std::printf("false-miss rate = wrong misses / reference hits; false-hit rate = wrong hits / reference misses;\n"
                "far errors = wrong decisions more than %.0f edge-ulps from any edge; closed-mesh misses are leaks.\n\n",
                kBand);
    std::printf("%-15s %-6s %-13s %9s %12s %12s %10s %10s\n", "policy", "prec", "category", "cases",
                "false-miss", "false-hit", "far-errors", "max-t-ulps");
    for (const Row& r : rows) {
        const double fm = r.reference_hits ? double(r.false_miss) / double(r.reference_hits) : 0.0;
        const std::size_t misses = r.cases - r.reference_hits;
        const double fh = misses ? double(r.false_hit) / double(misses) : 0.0;
        std::printf("%-15s %-6s %-13s %9zu %11.4f%% %11.4f%% %10zu %10.2g\n", r.policy.c_str(),
                    r.precision.c_str(), r.category.c_str(), r.cases, 100 * fm, 100 * fh, r.far_errors,
                    r.max_t_ulps);
    }
    if (!csv.empty()) {
        std::ofstream out(csv);
        if (!out) {
            std::fprintf(stderr, "cannot write %s\n", csv.c_str());
            return 1;
        }
        out << "policy,precision,category,cases,reference_hits,false_miss,false_hit,far_errors,max_t_ulps\n";
        for (const Row& r : rows)
            out << r.policy << ',' << r.precision << ',' << r.category << ',' << r.cases << ','
                << r.reference_hits << ',' << r.false_miss << ',' << r.false_hit << ',' << r.far_errors
                << ',' << r.max_t_ulps << '\n';
        std::printf("\nwrote %s\n", csv.c_str());
    }
    return 0;
}
