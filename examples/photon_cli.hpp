// photon_cli.hpp: glint-render's photon-mapping integrators (glint/photons): where the
// command line's values become their settings. Included by render.cpp and
// render_integrators.cpp (which defines its functions).
//
//   --integrator sppm      stochastic progressive photon mapping (photons/sppm.hpp): passes
//                          of one camera ray per pixel and --photons photons, direct light by
//                          MisDirect; --time-budget S runs passes for S seconds, else --spp
//                          passes
//   --integrator photons   photon mapping (photons/photon_integrator.hpp): direct light by
//                          MisDirect, caustics from the caustic map, indirect light by a final
//                          gather from the global map; --time-budget S runs passes of new maps
//                          (a seed each) and --spp samples per pixel for S seconds, averaged
//   --photons N            sppm: photons emitted per pass; photons: for the global map, and
//                          4 N for the caustic map (default 100000)
//   --radius R             sppm: initial gather radius; photons: largest kNN radius (scene
//                          units, default 0.05)
//   --camera-samples N     sppm: camera rays per pixel and pass for emission and direct light
//                          (one of them, sample k mod N in pass k, gathers the photons; default 1)
//   --knn K                photons: photons per radiance estimate (default 50)
//   --final-gather N       photons: final gather rays per pixel sample (default 64)
#pragma once

#include <cstdint>

#include <glint/photons/photon_integrator.hpp>
#include <glint/photons/sppm.hpp>
#include <glint/tracer/any_accel.hpp>
#include <glint/tracer/progressive.hpp>

namespace glint {

struct PhotonCliOptions {
    std::size_t photons = 100000;
    double radius = 0.05;
    int knn = 50;
    int gather_rays = 64;
    int camera_samples = 1;
};

/// SPPM of `scene` (traced through `accel`) at `image`'s size and threads: passes until
/// `budget` says stop. Defined in render_integrators.cpp.
SppmResult render_sppm_cli(const Scene<float>& scene, const AnyAccel& accel, const PhotonCliOptions& p,
                           const RenderSettings& image, const PassBudget& budget, std::uint64_t seed);

/// Photon mapping of `scene` (traced through `accel`): passes of new maps (seed + pass) and
/// `image`'s spp until `budget` says stop, averaged. Defined in render_integrators.cpp.
ProgressiveResult render_photons_cli(const Scene<float>& scene, const AnyAccel& accel, const PhotonCliOptions& p,
                                     const RenderSettings& image, const PassBudget& budget, std::uint64_t seed);

}  // namespace glint
