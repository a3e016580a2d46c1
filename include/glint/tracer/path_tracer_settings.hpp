// glint/tracer/path_tracer_settings.hpp: what the path tracer (tracer/path_tracer.hpp) and its
// lighting policies are set by: the roulette rule, the BRDF selection, the depth cap, the
// light samples per vertex and the neighbourhood over which correlated sampling pools its
// lambda. The image's settings (size, samples per pixel, threads) are the Renderer's
// (tracer/renderer.hpp's RenderSettings).
#pragma once

#include <glint/core/math.hpp>
#include <glint/sampling/roulette.hpp>

namespace glint {

/// The path tracer's per-walk settings, shared with its lighting policies (which read
/// light_samples and lambda_filter_radius); the defaults give MIS with one light sample.
template <Scalar T = float>
struct PathTracerSettings {
    /// The roulette rule (sampling/roulette.hpp); the field's throughput rule by default.
    Roulette<T, 3> roulette{};
    /// Cap on a walk's vertices, far beyond where roulette stops walks (a grey furnace of
    /// albedo 0.99 continues past 1024 vertices with probability about 3e-5); walks that reach
    /// it are counted in RenderStats::capped_walks, since a cap truncates (biases) them.
    int max_depth = 1024;
    /// The estimator of Szécsi 2009, §2.1 at diffuse and glossy vertices.
    BrdfSelection selection = BrdfSelection::mis;
    /// Light samples per area light and vertex (MisDirect, CorrelatedDirect).
    int light_samples = 1;
    /// CorrelatedDirect's combined estimator at the primary vertices: lambda from the
    /// statistics pooled over the (2r + 1)^2 pixel neighbourhood (Szécsi 2009, §3.1.1); -1
    /// estimates it per vertex.
    int lambda_filter_radius = 1;
};

}  // namespace glint
