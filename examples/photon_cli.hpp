// photon_cli.hpp: glint-render's photon-mapping integrators (glint/photons): where the
// command line's values become their settings. Included by render.cpp only.
//
//   --integrator sppm      stochastic progressive photon mapping (photons/sppm.hpp): passes
//                          of one camera ray per pixel and --photons photons, direct light by
//                          MisDirect; --time-budget S runs passes for S seconds, else --spp
//                          passes
//   --photons N            photons emitted per pass (default 100000)
//   --radius R             initial gather radius, scene units (default 0.05)
#pragma once

#include <cstdio>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/photons/sppm.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/progressive.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/trees/mesh_bvh.hpp>

namespace glint {

struct PhotonCliOptions {
    std::size_t photons = 100000;
    double radius = 0.05;
    int knn = 50;
};

/// SPPM of `scene` at `image`'s size and threads: passes until `budget` says stop.
inline SppmResult render_sppm_cli(const Scene<float>& scene, const PhotonCliOptions& p, const RenderSettings& image,
                                  const PassBudget& budget, std::uint64_t seed) {
    using Accel = MeshBvh<MollerTrumbore<float>, 8>;
    const Accel accel(scene.triangles);
    SppmSettings st;
    st.photons = p.photons;
    st.radius = p.radius;
    st.seed = seed;
    return render_sppm(scene, accel, MisDirect<float>(scene, PathTracerSettings<float>{}), image, st, budget);
}

}  // namespace glint
