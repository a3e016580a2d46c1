// bench_vpl: the VPL integrator (glint/vpl/integrator.hpp) with shadow rays through the wide
// BVH against occluder spheres (Szécsi 2009, ch. 5) on a mesh standing in the Cornell box (its two
// blocks removed: the mesh is the only occluder).
//
//   bench_vpl [--quick] [--mesh FILE.obj] [--size S] [--vpls N] [--spheres 25,100,400] [--threads T] [--csv FILE]
//
// The VPL (indirect) illumination only, as in the measurements of Szécsi 2009, Fig. 5.7: shooting
// once, then the same VPLs gathered with each visibility policy, each timed twice in alternation (the
// faster of the two kept). The occluders are generated from the mesh's triangles (the box's
// walls are a convex enclosure and occlude nothing inside). Prints seconds, the speedup over
// shadow rays, and the relative RMSE of the sphere image against the shadow-ray image (the
// visibility approximation's error, the VPLs being the same).
//   CSV columns: scene,visibility,spheres,seconds,speedup,rel_rmse
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/io/obj.hpp>
#include <glint/occluders/spheres.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/vpl/integrator.hpp>
#include "image_error.hpp"

#include "flags.hpp"  // cli/: the command-line conventions

using namespace glint;

namespace {

using Accel = MeshBvh<MollerTrumbore<float>, 8>;
using Img = std::vector<Rgb<float>>;

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

/// The faster of two timed gathers (the image of the last).
template <class V>
double timed_gather(const Scene<float>& s, std::span<const PixelPoint<float>> pts, std::span<const Vpl<float>> vpls, const V& vis,
                    int threads, Img& out) {
    double best = 1e30;
    for (int k = 0; k < 2; ++k) {
        const double t0 = now();
        out = gather_image(s, pts, vpls, vis, 0.0, threads);
        best = std::min(best, now() - t0);
    }
    return best;
}

}  // namespace

int main(int argc, char** argv) try {
    std::string mesh_path = "../shared/scenes/bunny.obj", csv;
    int size = 96, threads = 1;
    std::size_t walks = 512;
    std::vector<std::size_t> counts{25, 100, 400};
    cli::App app("bench_vpl: VPL rendering with occluder spheres against shadow rays at equal VPLs");
    // --quick first: the flags after it in this list (any given with it) override its sizes.
    app.flag("--quick", [&] { size = 16, walks = 16, counts = {25}; }, "a smoke run: 16 x 16, 16 walks, 25 spheres");
    cli::text(app, "--mesh", mesh_path, "FILE.obj: the occluding mesh");
    cli::number(app, "--size", size, 1, 1 << 14, "image width and height");
    cli::number(app, "--vpls", walks, std::size_t(1), std::size_t(1) << 24, "shooting walks");
    cli::number(app, "--threads", threads, 1, 4096, "threads");
    cli::output(app, "--csv", csv, "write the rows as CSV");
    cli::numbers(app, "--spheres", counts, std::size_t(1), std::size_t(1) << 20, "occluder sphere counts");
    if (!cli::parse(app, argc, argv)) return 0;
    // The Cornell box without its two blocks (its first 10 triangles are the 5 walls, the last
    // 2 the light), so that the mesh is the only occluder, as in bench_occluders.
    const Scene<float> full = builtin_scene<float>("cornell");
    Scene<float> scene = full;
    scene.triangles.clear(), scene.material_of.clear(), scene.light_of.clear();
    for (std::size_t i = 0; i < full.triangles.size(); ++i)
        if (i < 10 || full.light_of[i] >= 0) {
            scene.triangles.push_back(full.triangles[i]);
            scene.material_of.push_back(full.material_of[i]);
            scene.light_of.push_back(full.light_of[i]);
        }
    const std::size_t before = scene.triangles.size();
    insert_mesh<float>(scene, load_obj(mesh_path).triangles, Material<float>::lambertian(Rgb<float>(0.725f, 0.71f, 0.68f)),
                       cornell_mesh_placement<float>());
    const std::span<const TriangleVertices<float>> mesh(scene.triangles.data() + before, scene.triangles.size() - before);
    const Accel accel(scene.triangles);
    RenderSettings image;
    image.width = image.height = size;
    image.threads = threads;
    image.spp = 1;
    image.pixel_jitter = false;
    const auto points = primary_points(scene, accel, image, VplSettings{});
    const auto vpls = shoot_scene_vpls(scene, accel, Roulette<float, 3>::classic(), walks, 1);
    const std::span<const PixelPoint<float>> pts(points);
    const std::span<const Vpl<float>> vs(vpls);
    std::printf("%s in the Cornell box: %zu triangles, %zu VPLs, %dx%d\n", mesh_path.c_str(), mesh.size(), vpls.size(), size, size);
    std::ostringstream rows;
    Img ref, img;
    for (const std::size_t k : counts) {
        const auto spheres = generate_occluders(mesh, k);
        const std::span<const Sphere<float>> set(spheres);
        // Alternate: rays, then spheres, for every sphere count (the rays' time of this round).
        const double t_rays = timed_gather(scene, pts, vs, ShadowRayVisibility<Accel>(accel, 1e-4f), threads, ref);
        const double t_sph = spheres.size() < 800 ? timed_gather(scene, pts, vs, SphereVisibilityLinear<float>(set), threads, img)
                                                  : timed_gather(scene, pts, vs, SphereVisibilityKdTree<float>(set), threads, img);
        const double e = relative_rmse(std::span<const Rgb<float>>(img), std::span<const Rgb<float>>(ref));
        std::printf("spheres %4zu: rays %.3f s, spheres %.3f s, speedup %.1fx, rel. RMSE %.3f\n", spheres.size(), t_rays, t_sph,
                    t_rays / t_sph, e);
        rows << "bunny,rays,0," << t_rays << ",1,0\n"
             << "bunny,spheres," << spheres.size() << ',' << t_sph << ',' << t_rays / t_sph << ',' << e << '\n';
    }
    if (!csv.empty()) {
        std::ofstream out(csv);
        if (!out) throw Error("bench_vpl: cannot write '" + csv + "'");
        out << "scene,visibility,spheres,seconds,speedup,rel_rmse\n" << rows.str();
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
}
