// render_policies/render_options.hpp: glint-render's choice of the path tracer's policies by
// name (the command line, bench_convergence and the tracer tests use it).
//
// This is not part of the library: include/glint instantiates no policy combination. The
// combinations the names can reach are compiled once, split over several translation units
// of the glint_render_policies library (CMakeLists.txt next to this file), so that each of
// them compiles in seconds and a program that only renders pays for none of them.
//
// Names: roulette  classic | spectral | estimate | spectral+estimate (000's rules, from the
//                  first vertex); throughput | throughput+spectral | throughput+estimate |
//                  throughput+spectral+estimate (the field's throughput rule from
//                  rr_depth, with 000's spectral norm and radiance estimate on top); none
//                  (no roulette, throughput cut-off)
//        direct    brdf | mis | importance | correlated | combined
//        selection dis | w | mis
//        sampler   random | halton (= halton-perm) | halton-owen | halton-cp
//        accel     bvh8 (default) | bvh4 | kd-compact (accel_names())
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glint/core/ray.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/mesh_bvh.hpp>

namespace glint_cli {

using namespace glint;

/// The default accelerator: the 8-wide BVH with Moller-Trumbore leaves, glint's fastest tree
/// (docs/trees.md, "Wide BVH"). Its tracers are instantiated for it directly.
using RenderAccel = MeshBvh<MollerTrumbore<float>, 8>;

/// Any other accelerator --accel can name, behind one virtual call per ray: all of them share
/// one set of tracer instantiations (docs/tracer.md measures the call's cost).
class AnyAccel {
public:
    using scalar_type = float;
    virtual ~AnyAccel() = default;
    virtual bool closest_hit(const Ray<float>& ray, StoreHit<float>& hit) const = 0;
    virtual bool any_hit(const Ray<float>& ray) const = 0;
};

/// The accelerator names --accel takes; the first is the default.
const std::vector<std::string>& accel_names();
/// The accelerator `name` (not the default) built over `tris`; throws glint::Error for an
/// unknown name.
std::unique_ptr<AnyAccel> make_accel(const std::string& name, std::span<const TriangleVertices<float>> tris);

struct RenderOptions {
    RenderSettings settings{};
    /// The default is the field's throughput rule: bench_convergence finds it as efficient
    /// as any roulette on the Cornell scenes (docs/tracer.md); the radiance estimate on top
    /// of it is within the noise there and can make pixels negative (its continued walks
    /// subtract (1 - s)/s a L~).
    std::string roulette = "throughput";
    /// Throughput roulettes: vertices before the first roulette decision (ThroughputRoulette's
    /// min_depth).
    int rr_depth = 3;
    /// Roulette "none": walks stop once the throughput they carry on falls below this.
    float throughput_cutoff = 1e-3f;
    std::string direct = "mis";
    /// The default sampler is Halton with random digit permutations: 1.16x PCG's time per
    /// path, lower error at equal time from 8 spp on (docs/sampling.md), and stratified pixel
    /// samples, which the light's edges need (docs/tracer.md, "Peer comparison: Cycles").
    std::string sampler = "halton";
    std::uint64_t seed = 0;
    /// Band weights H of the roulettes (000 section 2.2): "luminance" (0.3086, 0.6094,
    /// 0.0820) or "mean" (1/3 each, matching an error measured equally over R, G, B).
    std::string roulette_weights = "luminance";
    /// Radiance-estimate roulettes (000 section 2.3): where L~ comes from. "pilot" (default):
    /// the least-squares constant over pilot paths (fitted_radiance_estimate), 000's "data
    /// gathered during a preprocessing phase"; "scene": 000's closed-scene formula
    /// a~ Phi_e / (pi S (1 - a~)). Measured (bench_convergence --analysis): on the open
    /// Cornell box the formula overestimates, goodness d = 1.08 (worse than no estimate, the
    /// case 000 says to avoid), the pilot's d = 0.83; on the furnace, whose radiance is 1
    /// everywhere, the pilot finds L~ = 1 and the roulette adds almost no variance.
    std::string radiance_estimate = "pilot";
    /// Radiance-estimate roulettes: shorten walks by the goodness d of the estimate measured
    /// on pilot paths (ReducedContinuation, 000 section 2.3).
    bool reduce_continuation = false;
    /// Pilot camera paths for "pilot" and reduce_continuation; their time is part of the
    /// render's time. 0: 1/32 of the render's camera paths, at least 1024, at most 4096.
    int pilot_paths = 0;
};

const std::vector<std::string>& roulette_names();
const std::vector<std::string>& direct_names();
BrdfSelection parse_selection(const std::string& s);

/// Renders `scene` with the accelerator `accel` (built over scene.triangles) and the named
/// policies.
RenderResult render(const Scene<float>& scene, const RenderAccel& accel, const RenderOptions& o);
RenderResult render(const Scene<float>& scene, const AnyAccel& accel, const RenderOptions& o);

}  // namespace glint_cli
