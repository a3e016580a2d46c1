// render_integrators.cpp: glint-render's integrators other than the path tracer (whose
// render_named is compiled once in instances/): the VPL integrator (vpl_cli.hpp) and the
// photon-mapping ones (photon_cli.hpp). Compiled at -O3; render.cpp, which parses the command
// line, reads and writes files and calls these, is compiled at -O1 (none of it is hot).
#include <cstdio>
#include <span>
#include <string>

#include <glint/core/error.hpp>
#include <glint/occluders/spheres.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/tracer/lighting.hpp>

#include "photon_cli.hpp"
#include "vpl_cli.hpp"

namespace glint {

// Each function is documented where it is declared (vpl_cli.hpp, photon_cli.hpp).

VplResult render_vpl_cli(const Scene<float>& scene, const AnyAccel& accel, std::span<const TriangleVertices<float>> mesh,
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

SppmResult render_sppm_cli(const Scene<float>& scene, const AnyAccel& accel, const PhotonCliOptions& p,
                           const RenderSettings& image, const PassBudget& budget, std::uint64_t seed) {
    SppmSettings st;
    st.photons = p.photons;
    st.radius = p.radius;
    st.camera_samples = p.camera_samples;
    st.seed = seed;
    return render_sppm(scene, accel, MisDirect<float>(scene, PathTracerSettings<float>{}), image, st, budget);
}

ProgressiveResult render_photons_cli(const Scene<float>& scene, const AnyAccel& accel, const PhotonCliOptions& p,
                                     const RenderSettings& image, const PassBudget& budget, std::uint64_t seed) {
    PhotonMapSettings st;
    st.photons = p.photons;
    st.caustic_photons = 4 * p.photons;
    st.knn = std::size_t(p.knn);
    st.radius = float(p.radius);
    st.gather_rays = p.gather_rays;
    st.threads = image.threads;
    const MisDirect<float> direct(scene, PathTracerSettings<float>{});
    return render_passes(budget, [&](int pass) {
        st.seed = seed + std::uint64_t(pass);
        return render_photon_map(scene, accel, direct, image, st);
    });
}

}  // namespace glint
