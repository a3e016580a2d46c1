// glint/lights/many_light_direct.hpp: Fernandez 2004's deterministic many-light systems —
// dense cuts (§5.2, lights/cut_direct.hpp), sparse sampling (§5.3, lights/sparse_direct.hpp)
// and local illumination environments (ch. 3, lights/lie_direct.hpp) — as one direct-lighting
// policy type whose system is a run-time value.
//
// Each system spends microseconds per vertex (a cut of tens to hundreds of nodes, a LIE
// lookup and its rays), so one branch on the system costs nothing measurable, while a type
// each would add a PathTracer instantiation per accelerator type and sampler to every program
// that chooses its policies by name (glint-render: 4 each; its build went from 48 to 76 CPU-s
// with the three as types of their own). The systems stay usable alone, as the types they are.
#pragma once

#include <utility>
#include <variant>

#include <glint/lights/cut_direct.hpp>
#include <glint/lights/lie_direct.hpp>
#include <glint/lights/sparse_direct.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/shading.hpp>

namespace glint {

/// A DirectLighting policy that forwards to one of Fernandez 2004's many-light systems, chosen
/// at run time; it behaves exactly as the system it holds.
template <Scalar T = float>
class ManyLightDirect : public NoPixelStatistics<T> {
public:
    using vertex_record = typename NoPixelStatistics<T>::vertex_record;  ///< Empty: no per-pixel statistics.
    /// The systems it can hold: dense cuts, sparse sampling, local illumination environments.
    using System = std::variant<CutDirect<T>, SparseDirect<T>, LieDirect<T>>;

    /// The policy running `system` (built beforehand, with its own settings).
    explicit ManyLightDirect(System system) : system_(std::move(system)) {}

    /// The held system's estimate of the direct light at sp.
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S& sampler, Q& queries, vertex_record* rec) const {
        return std::visit([&](const auto& d) { return d.estimate(sp, sampler, queries, rec); }, system_);
    }
    /// The held system's weight of area-light emission met at hit by `ray` (0 where its
    /// estimate already holds that light, else 1).
    T emission_weight(const Arrival<T>& from, const Ray<T>& ray, const StoreHit<T>& hit) const {
        return std::visit([&](const auto& d) { return d.emission_weight(from, ray, hit); }, system_);
    }
    /// The held system.
    const System& system() const { return system_; }

private:
    System system_;
};

}  // namespace glint
