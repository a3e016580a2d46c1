// vpl_cli.hpp: glint-render's --integrator vpl (the virtual light sources method of
// glint/vpl/integrator.hpp): where the command line's names become the VPL integrator's
// types. Included by render.cpp and render_integrators.cpp (which defines its functions).
//
//   --vpls N            shooting walks (default 1024; each leaves a VPL per diffuse hit)
//   --visibility NAME   rays (shadow rays through the --accel tree) or spheres (occluder spheres
//                       of Szécsi 2009, ch. 5, built from the --insert-mesh mesh, or from the
//                       --mesh mesh; the linear scan below 800 spheres, the kd-tree above)
//   --spheres K         occluder spheres (default 100)
//   --clamp D           clamp the VPL geometry term at distance D (default 0: unbiased)
//   --gather NAME       all (every VPL) or cuts (a light cut of the VPLs, lights/cuts.hpp)
// The shooting walks use the classic (albedo) roulette of Szécsi 2009, §2.1.
#pragma once

#include <span>
#include <string>

#include <glint/tracer/any_accel.hpp>
#include <glint/vpl/integrator.hpp>

namespace glint {

struct VplCliOptions {
    std::string visibility = "rays", gather = "all";
    std::size_t vpls = 1024, spheres = 100;
    double clamp = 0;
};

/// Renders `scene` (traced through `accel`) with the VPL integrator at `image`'s size and
/// threads, one camera ray through each pixel's centre; occluders (for spheres) are built
/// from `mesh`. Defined in render_integrators.cpp (compiled at -O3; render.cpp is not hot).
VplResult render_vpl_cli(const Scene<float>& scene, const AnyAccel& accel, std::span<const TriangleVertices<float>> mesh,
                         const VplCliOptions& v, RenderSettings image, VplSettings st);

}  // namespace glint
