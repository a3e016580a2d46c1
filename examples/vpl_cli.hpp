// vpl_cli.hpp: glint-render's --integrator vpl (the virtual light sources method of
// glint/vpl/integrator.hpp): where the command line's names become the VPL integrator's
// types. Included by render.cpp only.
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

#include <cstdio>
#include <span>
#include <string>

#include <glint/core/error.hpp>
#include <glint/occluders/spheres.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/tracer/any_accel.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/vpl/integrator.hpp>

namespace glint {

struct VplCliOptions {
    std::string visibility = "rays", gather = "all";
    std::size_t vpls = 1024, spheres = 100;
    double clamp = 0;
};

/// Renders `scene` (traced through `accel`) with the VPL integrator at `image`'s size and
/// threads, one camera ray through each pixel's centre; occluders (for spheres) are built
/// from `mesh`.
inline VplResult render_vpl_cli(const Scene<float>& scene, const AnyAccel& accel, std::span<const TriangleVertices<float>> mesh,
                                const VplCliOptions& v, RenderSettings image, VplSettings st) {
    const auto roulette = Roulette<float, 3>::classic();
    image.spp = 1;
    image.pixel_jitter = false;
    st.vpl_walks = v.vpls;
    st.min_distance = v.clamp;
    if (v.visibility == "rays")
        return render_vpl(scene, accel, roulette, ShadowRayVisibility<AnyAccel>(accel, 1e-4f), image, st);
    if (v.visibility != "spheres") throw Error("--visibility expects rays or spheres, not '" + v.visibility + "'");
    if (mesh.empty()) throw Error("--visibility spheres needs --insert-mesh or --mesh: the occluders are built from that mesh");
    const auto spheres = generate_occluders(mesh, v.spheres);
    std::fprintf(stderr, "glint-render: %zu occluder spheres from %zu triangles\n", spheres.size(), mesh.size());
    const std::span<const Sphere<float>> set(spheres);
    if (spheres.size() < 800) return render_vpl(scene, accel, roulette, SphereVisibilityLinear<float>(set), image, st);
    return render_vpl(scene, accel, roulette, SphereVisibilityKdTree<float>(set), image, st);
}

}  // namespace glint
