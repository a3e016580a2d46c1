// glint/lights/lie_direct.hpp: LieDirect, the direct-lighting policy that shades through local
// illumination environments (Fernandez 2004, §3.1.2 and §3.2; lights/lie.hpp builds them).
//
// At a vertex, the LIE of the cell holding it: absent lights are skipped, unoccluded ones are
// added with no visibility test, partial ones are tested against their blocker triangles only
// (the intersection/ test on each, no tree; the three-state variant casts an ordinary shadow
// ray instead). With masking (a run-time value), the lights the cell's masking dropped are
// skipped too. A vertex in a cell no construction sample reached (a secondary vertex off
// screen, a region the camera does not see) gets a plain shadow ray per light: exact there.
// The policy is deterministic and handles all the direct light of point lights and of area
// lights (as points on them, lie_lights()): emission_weight is 0 for area-light emission met
// by a ray leaving a vertex it shaded, 1 otherwise.
//
// Bias (lights/lie.hpp): wherever a cell's states are wrong for a point (a light or a blocker
// no sample found), the point gets that light wrongly; with masking, dropped light up to 2% of
// the cell's smallest sampled total, more at points the samples missed.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <type_traits>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/lights/lie.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/path_tracer_settings.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>
#include <glint/trees/brute_force.hpp>
#include <glint/trees/mesh_bvh.hpp>

namespace glint {

/// What shading one vertex cost: lights evaluated (f I cos / r^2), rays through the accelerator
/// (fallback, three-state partial lights), rays tested against blocker lists, and the
/// ray-triangle tests those took.
struct LieShadeCost {
    std::uint32_t lights = 0, accel_rays = 0, blocker_rays = 0, blocker_tests = 0;
    /// \var lights
    /// Lights evaluated (f I cos / r^2), those that could contribute.
    /// \var accel_rays
    /// Shadow rays through the accelerator (fallback cells, three-state partial lights).
    /// \var blocker_rays
    /// Shadow rays tested against blocker lists only.
    /// \var blocker_tests
    /// Ray-triangle tests against blocker list entries.
};

/// The DirectLighting policy that shades through local illumination environments (Fernandez
/// 2004, §3.1.2, §3.2): deterministic; copies share one Lie and may run on any number of threads.
template <Scalar T = float>
class LieDirect : public NoPixelStatistics<T> {
public:
    using vertex_record = typename NoPixelStatistics<T>::vertex_record;  ///< Empty: no per-pixel statistics.
    /// The accelerator the scene-only constructor builds for the construction's rays.
    using BuildAccel = std::conditional_t<std::is_same_v<T, float>, MeshBvh<MollerTrumbore<float>, 8>,
                                          BruteForce<MollerTrumbore<T>>>;

    /// The direct light at a vertex and what computing it cost.
    struct Shaded {
        Rgb<T> L{T(0)};     ///< Reflected direct radiance toward the vertex's outgoing direction.
        LieShadeCost cost;  ///< Lights evaluated, rays and triangle tests spent.
    };

    /// LIEs built through `accel` (over scene.triangles).
    template <RayAccelerator A>
    LieDirect(const Scene<T>& scene, const A& accel, const LieSettings& s, bool masking)
        : scene_(&scene), lie_(std::make_shared<const Lie<T>>(scene, accel, s)), masking_(masking) {}
    /// LIEs built through an accelerator of its own (what a factory that has none calls).
    LieDirect(const Scene<T>& scene, const LieSettings& s, bool masking)
        : LieDirect(scene, BuildAccel(std::span<const TriangleVertices<T>>(scene.triangles)), s, masking) {}

    /// The direct light at sp (shade()'s L); the sampler is not used.
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S&, Q& queries, vertex_record*) const {
        return shade(sp, queries).L;
    }

    /// 0 for area-light emission met by a ray from a vertex this policy shaded (its light is
    /// in the estimate already), 1 otherwise.
    T emission_weight(const Arrival<T>& from, const Ray<T>&, const StoreHit<T>& hit) const {
        return from.lights_sampled && scene_->light_of[hit.id] >= 0 ? T(0) : T(1);
    }

    /// The direct light at sp through the LIE of its cell, and what it cost.
    template <class Q>
        requires ShadowQueries<Q, T>
    Shaded shade(const ShadingPoint<T>& sp, Q& queries) const {
        const std::uint32_t c = lie_->locate(sp.x);
        if (c == LieOctree<T>::none) return shadow_rays(sp, queries);
        Shaded out;
        const bool lists = lie_->settings().variant == LieVariant::blocker_lists;
        for (const LieEntry& e : lie_->entries(c)) {
            if (masking_ && e.masked) continue;
            const LieLight<T>& l = lie_->lights()[e.light];
            Rgb<T> f;
            if (!point_light_unshadowed(l.light, sp, f)) continue;
            ++out.cost.lights;
            if (e.state == LieState::partial && !(lists ? through_blockers(sp, l, e, out.cost) : through_accel(sp, l, queries, out.cost)))
                continue;
            out.L += f;
        }
        return out;
    }

    /// Every light with a shadow ray through the accelerator: the standard ray tracer, and the
    /// fallback where no construction sample reached.
    template <class Q>
        requires ShadowQueries<Q, T>
    Shaded shadow_rays(const ShadingPoint<T>& sp, Q& queries) const {
        Shaded out;
        for (const LieLight<T>& l : lie_->lights()) {
            Rgb<T> f;
            if (!point_light_unshadowed(l.light, sp, f)) continue;
            ++out.cost.lights;
            if (through_accel(sp, l, queries, out.cost)) out.L += f;
        }
        return out;
    }

    /// The local illumination environments the policy shades through.
    const Lie<T>& lie() const { return *lie_; }
    /// Whether lights the cells' masking dropped are skipped.
    bool masking() const { return masking_; }
    /// The same LIEs (shared, not rebuilt) with masking on or off.
    LieDirect with_masking(bool on) const {
        LieDirect d = *this;
        d.masking_ = on;
        return d;
    }

private:
    bool through_blockers(const ShadingPoint<T>& sp, const LieLight<T>& l, const LieEntry& e, LieShadeCost& cost) const {
        const Ray<T> ray = lie_shadow_ray(sp, l);
        ++cost.blocker_rays;
        for (const auto& tri : lie_->blockers(e)) {
            ++cost.blocker_tests;
            TriangleHit<T> h;
            if (tri.intersect(ray, h)) return false;
        }
        return true;
    }
    template <class Q>
    static bool through_accel(const ShadingPoint<T>& sp, const LieLight<T>& l, Q& queries, LieShadeCost& cost) {
        ++cost.accel_rays;
        return queries.unoccluded(lie_shadow_ray(sp, l));
    }

    const Scene<T>* scene_;
    std::shared_ptr<const Lie<T>> lie_;
    bool masking_ = false;
};

}  // namespace glint
