// benchmarks/bench_sparse.cpp: Fernandez 2004's sparse sampling (interpolation, reconstruction
// cuts) against dense cuts and the standard ray tracer, direct light at primary hits
// (benchmarks/support/sparse_measure.hpp), on the many-light scenes of lights/scenes.hpp.
// Prints CSV scene,method,lights,lights_per_pixel,shadow_rays_per_pixel,seconds,error_E,rmse.
// Run pinned: taskset -c 1 bench_sparse.
//   --scene NAME        hall, kitchen, lie-hall or all (all)
//   --size N            image N x N (128)           --reps N     alternating repetitions (2)
//   --samples N,N,...   construction camera rays (5000)
//   --agreements T,...  reconstruction's t_interp (0.05)
//   --neighbours K      k nearest samples (8)        --quick      a small run
//   --threshold T       the cuts' threshold (0.02)   --max-nodes N  the cuts' largest size (300)
//   --max-radius F      the kernel's largest radius, a fraction of the scene's diagonal (0.1)
// After the CSV, "#" lines give each sparse row's fraction of pixels shaded by the dense cut and
// the seconds of its sample cuts (part of its seconds) and their bytes per sample.
#include <cstdio>
#include <exception>
#include <sstream>

#include <glint/tracer/scenes.hpp>

#include "support/args.hpp"
#include "support/sparse_measure.hpp"

namespace {
template <class T>
std::vector<T> list(const std::string& s) {
    std::vector<T> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, ',');) out.push_back(T(std::stod(item)));
    return out;
}
}  // namespace

int main(int argc, char** argv) try {
    glint::bench::Args a(argc, argv);
    glint::bench::SparseMeasureOptions o;
    std::string scene = "all";
    int size = 128;
    while (a.next()) {
        if (a.flag() == "--scene") scene = a.value();
        else if (a.flag() == "--size") size = a.number(8, 4096);
        else if (a.flag() == "--reps") o.reps = a.number(1, 100);
        else if (a.flag() == "--samples") o.samples = list<int>(a.value());
        else if (a.flag() == "--agreements") o.agreements = list<double>(a.value());
        else if (a.flag() == "--neighbours") o.neighbours = a.number(2, 32);
        else if (a.flag() == "--threshold") o.cut.threshold = std::stod(a.value());
        else if (a.flag() == "--max-nodes") o.cut.max_nodes = a.number(0, 16000);
        else if (a.flag() == "--max-radius") o.max_radius = std::stod(a.value());
        else if (a.flag() == "--quick") size = 24, o.samples = {300}, o.reps = 1;
        else a.unknown("bench_sparse [--scene NAME] [--size N] [--reps N] [--samples N,..] [--agreements T,..] [--neighbours K] [--threshold T] [--max-nodes N] [--max-radius F] [--quick]");
    }
    o.width = o.height = size;
    std::printf("scene,method,lights,lights_per_pixel,shadow_rays_per_pixel,seconds,error_E,rmse\n");
    for (const char* name : {"hall", "kitchen", "lie-hall"}) {
        if (scene != "all" && scene != name) continue;
        const auto s = glint::builtin_scene<float>(name);
        std::vector<glint::bench::SparseExtras> extras;
        const auto rows = glint::bench::measure_sparse(s, o, &extras);
        for (const auto& r : rows)
            std::printf("%s,%s,%zu,%.2f,%.2f,%.4f,%.5f,%.5g\n", r.scene.c_str(), r.method.c_str(), r.lights, r.lights_per_pixel,
                        r.shadow_rays_per_pixel, r.seconds, r.error_E, r.rmse);
        for (std::size_t i = 2; i < rows.size(); ++i)
            std::printf("# %s %s: %.1f%% of pixels by the dense cut; sample cuts %.4f s, %.0f bytes per sample\n", name,
                        rows[i].method.c_str(), 100 * extras[i].dense_share, extras[i].build_seconds, extras[i].bytes_per_sample);
        std::fflush(stdout);
    }
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_sparse: %s\n", e.what());
    return 1;
}
