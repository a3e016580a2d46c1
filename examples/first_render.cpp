// first_render: the Cornell box through glint's path tracer into an EXR, in one screen.
#include <cstdio>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/io/exr.hpp>
#include <glint/sampling/halton.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>

int main(int argc, char** argv) {
    using namespace glint;
    const Scene<float> scene = builtin_scene<float>("cornell");  // or a Scene of your own
    using Bvh = MeshBvh<MollerTrumbore<float>, 8>;                // glint's fastest tree
    const Bvh bvh(scene.triangles);
    // Types where they pay in the hot loop (tree, sampler, direct lighting); values for the rest.
    const PathTracer<Bvh, HaltonSampler<float>, MisDirect<float>> tracer(
        scene, bvh, {.roulette = Roulette<float, 3>::throughput(), .max_depth = 64});
    const RenderSettings image{.width = 256, .height = 256, .spp = 64};
    const HaltonSampler<float> sampler(image.width, image.height, 18, HaltonRandomization::digit_permutation);
    const Renderer renderer(PixelCamera<float>(scene.camera, image), image);  // tiles, threads, film
    const RenderResult r = renderer.render(tracer, sampler);
    write_exr(argc > 1 ? argv[1] : "cornell.exr", r.image);
    std::printf("%.2f s, %.1f Mrays/s\n", r.seconds, double(r.rays) / r.seconds * 1e-6);
}
