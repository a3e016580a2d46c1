// benchmarks/bench_lie.cpp: local illumination environments against the standard ray tracer
// (benchmarks/support/lie_measure.hpp) on the LIE hall (tests/support/lie_hall.hpp): 100 point
// lights, 40 tessellated columns. Prints CSV scene,method,lights,lights_per_pixel,
// shadow_rays_per_pixel,seconds,error_E,rmse. Run pinned: taskset -c 1 bench_lie.
//   --size N      image N x N (256)        --samples N   LIE construction samples (131072)
//   --sides N     column facets (64)       --rings N     column rings (64)
//   --reps N      alternating repetitions (3)   --quick   a small run
//   --depth N     fixed octree depth (6)   --adaptive T  adaptive to depth 8, split past T blockers
//   --three-state three-state LIEs
#include <cstdio>
#include <exception>

#include "lie_hall.hpp"
#include "support/args.hpp"
#include "support/lie_measure.hpp"

int main(int argc, char** argv) try {
    glint::bench::Args a(argc, argv);
    glint::bench::LieMeasureOptions o;
    o.lie.samples = 1 << 17;
    int sides = 64, rings = 64, size = 256;
    while (a.next()) {
        if (a.flag() == "--size") size = a.number(8, 4096);
        else if (a.flag() == "--samples") o.lie.samples = a.number(1, 1 << 26);
        else if (a.flag() == "--sides") sides = a.number(3, 1024);
        else if (a.flag() == "--rings") rings = a.number(1, 1024);
        else if (a.flag() == "--reps") o.reps = a.number(1, 100);
        else if (a.flag() == "--depth") o.lie.depth = a.number(0, 20);
        else if (a.flag() == "--adaptive") o.lie.subdivision = glint::LieSubdivision::adaptive, o.lie.blocker_threshold = a.number(1, 1 << 20);
        else if (a.flag() == "--three-state") o.lie.variant = glint::LieVariant::three_state;
        else if (a.flag() == "--quick") size = 32, o.lie.samples = 4096, sides = 8, rings = 2, o.reps = 1;
        else a.unknown("bench_lie [--size N] [--samples N] [--sides N] [--rings N] [--reps N] [--depth N] [--adaptive T] [--three-state] [--quick]");
    }
    o.width = o.height = size;
    const auto scene = glint::lie_hall(100, 10, sides, rings);
    std::printf("# %zu triangles, %d construction samples, depth %d, %s, %s\n", scene.triangles.size(), o.lie.samples, o.lie.depth,
                o.lie.subdivision == glint::LieSubdivision::adaptive ? "adaptive" : "fixed",
                o.lie.variant == glint::LieVariant::three_state ? "three states" : "blocker lists");
    std::printf("scene,method,lights,lights_per_pixel,shadow_rays_per_pixel,seconds,error_E,rmse\n");
    const auto rows = glint::bench::measure_lie(scene, o);
    for (const auto& r : rows)
        std::printf("%s,%s,%zu,%.2f,%.2f,%.4f,%.5f,%.5g\n", r.scene.c_str(), r.method.c_str(), r.lights, r.lights_per_pixel,
                    r.shadow_rays_per_pixel, r.seconds, r.error_E, r.rmse);
    for (const auto& r : rows) std::printf("# %s: %.1f blocker tests per pixel\n", r.method.c_str(), r.blocker_tests_per_pixel);
} catch (const std::exception& e) {
    std::fprintf(stderr, "bench_lie: %s\n", e.what());
    return 1;
}
