// glint/tracer/lighting.hpp: the path tracer's lighting policies, each owning what it does.
//
// Direct lighting (area lights; a DirectLighting policy):
//   BrdfOnlyDirect    no next-event estimation: the walk collects emission where it hits it.
//   MisDirect         light sampling (light by power, then uniform area) and the BRDF sample,
//                     combined by the balance heuristic (Veach and Guibas 1995); the BRDF
//                     sample is the walk's continuation ray, so a vertex costs one closest-hit
//                     ray and one shadow ray per light sample.
//   CorrelatedDirect  Szécsi 2009, §3.2: multiple correlated sampling of polygon lights, with
//                     the importance, correlated or combined estimator fixed at construction;
//                     the combined estimator's lambda pooled over pixel neighbourhoods (§3.1.1)
//                     from statistics the policy keeps per pixel and turns into the film's
//                     values once, when the render is finished (tracer/correlated_direct.hpp).
// Environment lighting (an EnvironmentLighting policy): MisEnvironment (the map's importance
// sampling and the BRDF sample by the balance heuristic; nothing in a scene without a map);
// CorrelatedEnvironment (Szécsi 2009, §3.3) is in tracer/correlated_environment.hpp.
// A policy written anywhere (a test defines one) plugs into PathTracer unchanged: the concepts
// below name everything the tracer asks of it.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/lights/light_bounds.hpp>
#include <glint/lights/light_tree.hpp>
#include <glint/sampling/correlated.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/environment.hpp>
#include <glint/tracer/path_tracer_settings.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>

namespace glint {

/// What the path tracer asks of a direct-lighting policy D, for scalar T, ray queries Q and
/// sampler S:
///   estimate(sp, s, q, rec)  area lights' direct light at sp (rec: the primary vertex's record,
///                            else null; the policy may keep part of the estimate in it); 0 for
///                            a policy that samples no lights
///   emission_weight(from, ray, hit)  weight of area-light emission met at hit by `ray`, which
///                            left a vertex as `from` says (1 for a policy that samples no
///                            lights, and wherever `from` sampled none)
///   record(state, rec, L)    once per pixel sample: the primary record and the sample's L
///   finish(film, states)     once per render, after every sample: the policy's film values
template <class D, class T, class Q, class S>
concept DirectLighting =
    std::default_initializable<typename D::pixel_state> && std::default_initializable<typename D::vertex_record> &&
    requires(const D& d, const ShadingPoint<T>& sp, S& sampler, Q& queries, typename D::vertex_record* rec,
             typename D::pixel_state& state, const typename D::vertex_record& crec, const Rgb<T>& L, const Arrival<T>& from,
             const Ray<T>& ray, const StoreHit<T>& hit, Film& film, std::span<const typename D::pixel_state> states) {
        { d.estimate(sp, sampler, queries, rec) } -> std::same_as<Rgb<T>>;
        { d.emission_weight(from, ray, hit) } -> std::same_as<T>;
        d.record(state, crec, L);
        d.finish(film, states);
    };

/// What the path tracer asks of an environment-lighting policy: its light-sampled share at a
/// vertex, and the weighted radiance of a ray that escapes after leaving a vertex as `from`.
template <class E, class T, class Q, class S>
concept EnvironmentLighting = requires(const E& e, const ShadingPoint<T>& sp, S& sampler, Q& queries, const Vec3<T>& dir,
                                       const Arrival<T>& from) {
    { e.estimate(sp, sampler, queries) } -> std::same_as<Rgb<T>>;
    { e.escaped(dir, from) } -> std::same_as<Rgb<T>>;
};

/// For policies that keep no per-pixel statistics: empty records and nothing to finish.
template <Scalar T>
struct NoPixelStatistics {
    struct pixel_state {};
    struct vertex_record {};
    /// Keeps nothing (DirectLighting's per-sample hook).
    void record(pixel_state&, const vertex_record&, const Rgb<T>&) const {}
    template <class F>
    /// Adds nothing to the film (DirectLighting's end-of-render hook).
    void finish(F&, std::span<const pixel_state>) const {}
};

/// The balance heuristic's weight of a strategy of density a against one of density b.
template <Scalar T>
T balance_weight(T a, T b) {
    return a + b > T(0) ? a / (a + b) : T(0);
}

/// The scene's emitters: its area lights as polygon lights and its point lights, numbered in
/// that order (as scene_light_bounds numbers them); pick() chooses one in proportion to its
/// power (Le A for an area light, I measure / pi for a point light: both power / pi).
template <Scalar T>
class SceneLights {
public:
    /// An emitter index with the probability it was picked with.
    using Pick = LightPick<T>;

    /// The emitters of `scene`, with the power CDF pick() draws from; O(lights). Keeps copies,
    /// not references, of the lights.
    explicit SceneLights(const Scene<T>& scene) : points_(scene.point_lights) {
        for (const auto& l : scene.area_lights) {
            lights_.emplace_back(std::span<const Vec3<T>>(l.vertices), l.emission);
            power_ += l.emission.luminance() * l.area;
            cdf_.push_back(power_);
        }
        for (const auto& l : points_) {
            power_ += l.power().luminance() / pi<T>;
            cdf_.push_back(power_);
        }
    }
    /// The area lights (emitters 0 .. lights().size() - 1).
    const std::vector<PolygonLight<T, 3>>& lights() const { return lights_; }
    /// The point lights (emitters lights().size() ..).
    const std::vector<PointLight<T>>& point_lights() const { return points_; }
    /// No area lights (point lights are not sampled by every policy).
    bool empty() const { return lights_.empty(); }
    /// Number of emitters, area and point lights together.
    std::size_t emitters() const { return cdf_.size(); }

    /// The emitter chosen by u (proportional to power) and its probability.
    Pick pick(T u) const {
        if (!(power_ > T(0))) return {};
        std::size_t i = std::size_t(std::upper_bound(cdf_.begin(), cdf_.end(), u * power_) - cdf_.begin());
        i = std::min(i, cdf_.size() - 1);
        return {i, probability(i)};
    }
    /// Probability that pick() chooses emitter i (i < emitters(); the scene must have power > 0).
    T probability(std::size_t i) const { return (cdf_[i] - (i ? cdf_[i - 1] : T(0))) / power_; }
    /// Light-sampling density (solid angle, light chosen by power) of the direction towards a
    /// point of area light `l` at squared distance r2, seen under cosine cos_l there.
    T pdf(const AreaLight<T>& l, T r2, T cos_l) const { return l.emission.luminance() / power_ * r2 / cos_l; }

private:
    std::vector<PolygonLight<T, 3>> lights_;
    std::vector<PointLight<T>> points_;
    std::vector<T> cdf_;
    T power_ = 0;
};

/// Point light pl's direct light at sp, by one shadow ray: f I cos / r^2 (no ray behind the
/// shading plane or outside the light's cone).
template <Scalar T, class Q>
    requires ShadowQueries<Q, T>
Rgb<T> point_light_direct(const PointLight<T>& pl, const ShadingPoint<T>& sp, Q& queries) {
    Rgb<T> L;
    if (!point_light_unshadowed(pl, sp, L) || !queries.visible(sp, pl.position, Vec3<T>(T(0)), Vec3<T>(T(0))))
        return Rgb<T>(T(0));
    return L;
}

/// Every point light at sp, one shadow ray each (the standard ray tracer's loop): the point
/// lights' share of direct light for the policies that cannot sample them.
template <Scalar T, class Q>
    requires ShadowQueries<Q, T>
Rgb<T> all_point_lights(std::span<const PointLight<T>> lights, const ShadingPoint<T>& sp, Q& queries) {
    Rgb<T> L(T(0));
    for (const auto& pl : lights) L += point_light_direct(pl, sp, queries);
    return L;
}

/// How MisDirect chooses the emitter of a light sample.
enum class LightSelection : std::uint8_t { power, tree };

/// The emitter of a light sample, chosen by power (SceneLights) or by the stochastic light
/// tree (lights/light_tree.hpp) at the shading point: a run-time choice.
template <Scalar T>
class LightSelector {
public:
    /// The selector for `scene`'s emitters; LightSelection::tree also builds the light tree
    /// (O(n log n) in the emitters).
    LightSelector(const Scene<T>& scene, LightSelection how)
        : lights_(scene), how_(how),
          tree_(how == LightSelection::tree ? LightTree<T>(scene_light_bounds(scene)) : LightTree<T>()) {}

    /// The scene's emitters, in the numbering pick() returns.
    const SceneLights<T>& lights() const { return lights_; }
    /// By power or by the light tree, as constructed.
    LightSelection selection() const { return how_; }
    /// The light tree; empty unless selection() is LightSelection::tree.
    const LightTree<T>& tree() const { return tree_; }

    /// An emitter for point x with normal n, by u; probability 0: none.
    LightPick<T> pick(const Vec3<T>& x, const Vec3<T>& n, T u) const {
        return how_ == LightSelection::tree ? tree_.pick(x, n, u) : lights_.pick(u);
    }
    /// Probability that pick(x, n, ·) chooses emitter i: the density MIS weights need.
    T probability(const Vec3<T>& x, const Vec3<T>& n, std::size_t i) const {
        return how_ == LightSelection::tree ? tree_.probability(x, n, i) : lights_.probability(i);
    }
    /// Light-sampling density (solid angle) from x of a point of area light i at squared
    /// distance r2 seen under cosine cos_l there.
    T area_pdf(const Vec3<T>& x, const Vec3<T>& n, std::size_t i, const AreaLight<T>& l, T r2, T cos_l) const {
        if (how_ == LightSelection::power) return lights_.pdf(l, r2, cos_l);
        return tree_.probability(x, n, i) / l.area * r2 / cos_l;
    }

private:
    SceneLights<T> lights_;
    LightSelection how_;
    LightTree<T> tree_;
};

/// No next-event estimation of the area lights: the walk collects their emission wherever it
/// hits it, whole. Point lights, which no walk can hit, get one shadow ray each.
template <Scalar T = float>
struct BrdfOnlyDirect : NoPixelStatistics<T> {
    BrdfOnlyDirect() = default;
    /// The policy for `scene` (keeps a copy of its point lights; the settings are unused).
    BrdfOnlyDirect(const Scene<T>& scene, const PathTracerSettings<T>&) : points_(scene.point_lights) {}
    /// The point lights' direct light at sp, one shadow ray each; area lights add nothing here.
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S&, Q& queries, typename NoPixelStatistics<T>::vertex_record*) const {
        return all_point_lights(std::span<const PointLight<T>>(points_), sp, queries);
    }
    /// 1: the walk counts area-light emission wherever it meets it.
    T emission_weight(const Arrival<T>&, const Ray<T>&, const StoreHit<T>&) const { return T(1); }

private:
    std::vector<PointLight<T>> points_;
};

/// Light sampling and the BRDF sample combined by the balance heuristic (with sample counts:
/// k light samples and the one continuation ray, Veach and Guibas 1995). A light sample
/// chooses one emitter of the scene (area or point light) by the selector, by power or by the
/// light tree at the vertex; a point light's sample is its one shadow ray (weight 1: no BRDF
/// sample can hit it).
template <Scalar T = float>
class MisDirect : public NoPixelStatistics<T> {
public:
    /// Empty: MisDirect keeps nothing per vertex.
    using vertex_record = typename NoPixelStatistics<T>::vertex_record;

    /// The policy for `scene` (kept by reference: it must outlive the policy), taking
    /// s.light_samples (at least 1) light samples per vertex, emitters chosen by `how`.
    MisDirect(const Scene<T>& scene, const PathTracerSettings<T>& s, LightSelection how = LightSelection::power)
        : scene_(&scene), selector_(scene, how), k_(std::max(1, s.light_samples)) {}

    /// How light samples choose their emitter.
    const LightSelector<T>& selector() const { return selector_; }

    /// The light-sampled share of direct light at sp: k light samples, each an emitter, a point
    /// on it (area light) and one shadow ray, MIS-weighted against the BRDF sample.
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S& sampler, Q& queries, vertex_record*) const {
        Rgb<T> L(T(0));
        for (int i = 0; i < k_; ++i) L += light_sample(sp, sampler, queries);
        return L;
    }

    /// The BRDF sample's balance-heuristic weight where its ray meets area-light emission;
    /// the light-sampling density is the selector's at the vertex the ray left.
    T emission_weight(const Arrival<T>& from, const Ray<T>& ray, const StoreHit<T>& hit) const {
        if (!from.lights_sampled) return T(1);
        const T brdf_pdf = from.pdf;
        const std::int32_t li = scene_->light_of[hit.id];
        if (li < 0) return T(1);  // emissive but not a sampled light: only BRDF sampling finds it
        const auto& al = scene_->area_lights[std::size_t(li)];
        const T len2 = glm::dot(ray.direction, ray.direction);
        const T cos_l = -glm::dot(ray.direction, al.normal) / std::sqrt(len2);
        if (!(cos_l > T(0))) return T(0);
        const T pdf_light = selector_.area_pdf(from.x, from.n, std::size_t(li), al, hit.t * hit.t * len2, cos_l);
        return brdf_pdf / (brdf_pdf + T(k_) * pdf_light);
    }

private:
    /// One light sample: an emitter by the selector, then (area light) a point uniform on it:
    /// f Le cos / (k p_light + p_brdf); or (point light) f I cos / (r^2 k p_select).
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> light_sample(const ShadingPoint<T>& sp, S& sampler, Q& queries) const {
        const T u_light = sampler.get_1d();
        const Vec2<T> u_point = sampler.get_2d();
        const auto pick = selector_.pick(sp.x, sp.n, u_light);
        if (!(pick.probability > T(0))) return Rgb<T>(T(0));
        const auto& areas = selector_.lights().lights();
        if (pick.index >= areas.size()) {
            const auto& pl = selector_.lights().point_lights()[pick.index - areas.size()];
            return point_light_direct(pl, sp, queries) * (T(1) / (T(k_) * pick.probability));
        }
        const auto& light = areas[pick.index];
        const Vec3<T> y = light.sampler().sample(u_point);
        const Vec3<T> d = y - sp.x;
        const T r2 = glm::dot(d, d);
        const Vec3<T> wi = d / std::sqrt(r2);
        const T cos_l = -glm::dot(wi, light.sampler().normal());
        const Vec3<T> wl = sp.frame.to_local(wi);
        if (!(cos_l > T(0)) || wl.z <= T(0)) return Rgb<T>(T(0));
        const T pdf_light = pick.probability / light.sampler().area() * r2 / cos_l;
        const Rgb<T> f = sp.brdf->f(wl);
        if (f.max() <= T(0) || !queries.visible(sp, light, y)) return Rgb<T>(T(0));
        return light.radiance() * f * (wl.z / (T(k_) * pdf_light + sp.brdf->sampling_pdf(wl)));
    }
    const Scene<T>* scene_;
    LightSelector<T> selector_;
    int k_;
};

/// The environment map sampled by its importance (one sample per vertex) and by the BRDF
/// sample (the continuation ray), combined by the balance heuristic. In a scene without a map
/// it draws no samples and adds nothing (one predictable branch per vertex).
template <Scalar T = float>
class MisEnvironment {
public:
    MisEnvironment() = default;
    /// The policy for `scene`'s environment map, kept by pointer (the scene must outlive the
    /// policy); a scene without a map makes it a no-op.
    explicit MisEnvironment(const Scene<T>& scene) : env_(scene.environment ? &*scene.environment : nullptr) {}

    /// The map's light-sampled share at sp: one direction from the map's importance (a 2D number
    /// from `sampler`) and its shadow ray, balance-weighted against the BRDF sample.
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S& sampler, Q& queries) const {
        if (!env_) return Rgb<T>(T(0));
        const Vec2<T> u_env = sampler.get_2d();
        T pdf_env;
        const Vec3<T> we = env_->sample(u_env, pdf_env);
        const Vec3<T> wl = sp.frame.to_local(we);
        if (!(pdf_env > T(0)) || wl.z <= T(0)) return Rgb<T>(T(0));
        const Rgb<T> f = sp.brdf->f(wl);
        if (f.max() <= T(0) || !queries.unoccluded(spawn(sp, we))) return Rgb<T>(T(0));
        return env_->eval(we) * f * (wl.z * balance_weight(pdf_env, sp.brdf->sampling_pdf(wl)) / pdf_env);
    }
    /// Map radiance in direction `dir` for a ray escaping the scene, balance-weighted against the
    /// map sample when the vertex it left sampled lights (else whole).
    Rgb<T> escaped(const Vec3<T>& dir, const Arrival<T>& from) const {
        if (!env_) return Rgb<T>(T(0));
        const T w = from.lights_sampled ? balance_weight(from.pdf, env_->pdf(safe_normalize(dir))) : T(1);
        return env_->eval(dir) * w;
    }

private:
    const EnvironmentMap<T>* env_ = nullptr;
};

}  // namespace glint
