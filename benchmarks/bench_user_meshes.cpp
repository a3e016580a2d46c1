// bench_user_meshes: bench_trees --user-meshes as a program of its own, with only the tree type a
// user's renderer has (MeshBvh<MollerTrumbore<float>, 8>, support/user_meshes.hpp) in its
// translation unit. bench_trees instantiates dozens of tree, layout and intersector types in
// one unit, where GCC's unit-wide inlining budget runs out in a build without -march flags and
// leaves the run-time kernels' box test out of line; a renderer's unit looks like this one.
//
//   bench_user_meshes [--scenes DIR] [--only STEM] [--no-generated] [--rays N] [--primary N]
//                     [--reps N] [--builds N] [--isa NAME] [--csv FILE] [--cpu-time]
//
// The same rows, printout and CSV columns as bench_trees --user-meshes (which runs the same
// code); tools/portable_native.py compares this program built with and without -march.
#include <cstddef>
#include <cstdio>
#include <string>

#include "flags.hpp"  // cli/: the command-line conventions
#include "support/clock.hpp"
#include "support/obj_reader.hpp"
#include "support/user_meshes.hpp"

using namespace glint;

#ifdef GLINT_HAVE_EMBREE
namespace {

/// The command line: the mode's options (support/user_meshes.hpp) and the CSV file.
bench::UserMeshOptions parse(int argc, char** argv, std::string& csv) {
    bench::UserMeshOptions o;
    o.scenes = GLINT_BENCH_SCENES;
    cli::App app("bench_user_meshes: every mesh of --scenes through MeshBvh's public API against Embree 3");
    cli::text(app, "--scenes", o.scenes, "the folder of OBJ meshes", "DIR");
    cli::text(app, "--only", o.only, "only this mesh (file stem)", "STEM");
    app.flag("--no-generated", [&o] { o.generated = false; }, "leave out the generated scenes");
    cli::number(app, "--rays", o.rays, std::size_t(1), std::size_t(1) << 40, "incoherent and any-hit rays per mesh");
    cli::number(app, "--primary", o.primary, 1, 8192, "N x N primary rays");
    cli::number(app, "--reps", o.reps, 1, 1000, "alternating timed passes (median)");
    cli::number(app, "--builds", o.builds, 1, 1000, "alternating builds per mesh (median)");
    app.value("--isa", [&o](const std::string& name) { return bench::parse_isa(name, o.isa); },
              "glint's kernels (default: the best this CPU runs)", "NAME", isa_name(best_isa()));
    cli::output(app, "--csv", csv, "write the rows as CSV (bench_trees' columns)");
    cli::flag(app, "--cpu-time", bench::PassClock::thread_cpu, "time passes by the thread's CPU clock, not the wall clock");
    cli::parse_or_exit(app, argc, argv, "bench_user_meshes");
    return o;
}

}  // namespace

int main(int argc, char** argv) try {
    std::string csv;
    const bench::UserMeshOptions o = parse(argc, argv, csv);
    const auto rows = bench::run_user_meshes(o, [](const std::string& f) { return bench::read_obj(f); });
    if (!csv.empty()) bench::write_user_csv(csv, rows);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_user_meshes: %s\n", e.what());
    return 1;
}
#else
int main() {
    std::fputs("bench_user_meshes: needs Embree 3 (not found at configure time)\n", stderr);
    return 1;
}
#endif
