// glint/lights/cut_direct.hpp: dense light cuts (Fernandez 2004, §5.2) as the path tracer's
// direct-lighting policy (the DirectLighting concept of tracer/lighting.hpp).
//
// CutDirect holds a light cluster tree (lights/cluster_tree.hpp) over the lights it was given
// (lights/light_points.hpp: by default the scene's point lights and its polygon area lights,
// each split into oriented points) and at every diffuse or glossy vertex returns the cut's sum
// (lights/cuts.hpp), one shadow ray per node of the cut. It is deterministic and biased: the
// split of an area light into points, and each node's cluster approximation (at most twice
// the threshold times the point's total, per node, with the default error estimate). It
// accounts for all direct light of its lights: a BRDF-sampled ray that meets the emission of
// an area light it covers counts it with weight 0 (camera rays and specular bounces count it
// whole). Its knobs (threshold, largest cut, how finely area lights are split) are run-time
// values. The point lights it is not given get no light at all: the path tracer leaves every
// emitter to its direct-lighting policy.
#pragma once

#include <algorithm>
#include <concepts>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/lights/cluster_tree.hpp>
#include <glint/lights/cuts.hpp>
#include <glint/lights/light_points.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/lighting.hpp>
#include <glint/tracer/path_tracer_settings.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>

namespace glint {

/// What CutDirect asks of a sample's ray queries: a shadow ray from sp to point y (rounding
/// error y_err, on a surface of normal ny; zeros for a point in space).
template <class Q, class T>
concept PointShadowQueries = requires(Q& q, const ShadingPoint<T>& sp, const Vec3<T>& y) {
    { q.visible(sp, y, y, y) } -> std::convertible_to<bool>;
};

/// Dense light cuts (Fernandez 2004, §5.2) as a DirectLighting policy: deterministic, one shadow
/// ray per node of the cut; copies share one cluster tree and may run on any number of threads.
template <Scalar T = float>
class CutDirect : public NoPixelStatistics<T> {
public:
    using vertex_record = typename NoPixelStatistics<T>::vertex_record;  ///< Empty: no per-pixel statistics.

    /// The scene's point lights and area lights (split into LightPointOptions' default count
    /// of points), the default cut (2%, 300 nodes).
    CutDirect(const Scene<T>& scene, const PathTracerSettings<T>&) : CutDirect(scene, LightPointOptions<T>{}, CutSettings{}) {}

    /// The lights `lights` selects from `scene`, split as it says, under cut settings `cut`.
    /// Throws Error when `cut` or a light is invalid. Builds the cluster tree (O(n log n));
    /// `scene` must outlive the policy.
    CutDirect(const Scene<T>& scene, const LightPointOptions<T>& lights, const CutSettings& cut)
        : scene_(&scene), covers_area_lights_(lights.area_lights), cut_(cut) {
        cut.validate();
        auto tree = std::make_shared<const LightClusterTree<T>>(scene_light_points(scene, lights));
        tree_ = std::move(tree);
    }

    /// Direct light reflected at sp toward its outgoing direction: the cut's sum over the tree's
    /// lights, one shadow ray through `queries` per node of the cut; the sampler is not used.
    template <class Q, class S>
        requires PointShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S&, Q& queries, vertex_record*) const {
        const CutReceiver<T> r{sp.x, sp.n, sp.frame, sp.brdf, T(0)};
        return evaluate_cut(*tree_, r, cut_, [&](const PointLight<T>& l) { return visible(sp, l, queries); }).L;
    }

    /// 0 for emission of an area light the cut accounts for, met by a BRDF-sampled ray.
    T emission_weight(const Arrival<T>& from, const Ray<T>&, const StoreHit<T>& hit) const {
        return from.lights_sampled && covers_area_lights_ && scene_->light_of[hit.id] >= 0 ? T(0) : T(1);
    }

    /// The cluster tree over the policy's lights.
    const LightClusterTree<T>& tree() const { return *tree_; }
    /// The cut settings the policy was built with.
    const CutSettings& settings() const { return cut_; }

    /// A shadow ray to light l; an oriented point lies on a surface, so its end is offset off it.
    template <class Q>
    static bool visible(const ShadingPoint<T>& sp, const PointLight<T>& l, Q& queries) {
        if (l.kind != PointLightKind::cosine) return queries.visible(sp, l.position, Vec3<T>(T(0)), Vec3<T>(T(0)));
        const Vec3<T> a = glm::abs(l.position);
        return queries.visible(sp, l.position, coordinate_error(std::max({a.x, a.y, a.z})), l.axis);
    }

private:
    const Scene<T>* scene_;
    bool covers_area_lights_;
    CutSettings cut_;
    std::shared_ptr<const LightClusterTree<T>> tree_;  // shared by the tracer's copies
};

}  // namespace glint
