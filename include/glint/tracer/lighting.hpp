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
    void record(pixel_state&, const vertex_record&, const Rgb<T>&) const {}
    template <class F>
    void finish(F&, std::span<const pixel_state>) const {}
};

/// The balance heuristic's weight of a strategy of density a against one of density b.
template <Scalar T>
T balance_weight(T a, T b) {
    return a + b > T(0) ? a / (a + b) : T(0);
}

/// The scene's area lights as polygon lights, chosen in proportion to their power.
template <Scalar T>
class SceneLights {
public:
    struct Pick {
        std::size_t index;
        T probability;
    };

    explicit SceneLights(const Scene<T>& scene) {
        for (const auto& l : scene.area_lights) {
            lights_.emplace_back(std::span<const Vec3<T>>(l.vertices), l.emission);
            power_ += l.emission.luminance() * l.area;
            cdf_.push_back(power_);
        }
    }
    const std::vector<PolygonLight<T, 3>>& lights() const { return lights_; }
    bool empty() const { return lights_.empty(); }

    /// The light chosen by u (proportional to power) and its probability.
    Pick pick(T u) const {
        std::size_t i = std::size_t(std::upper_bound(cdf_.begin(), cdf_.end(), u * power_) - cdf_.begin());
        i = std::min(i, lights_.size() - 1);
        return {i, (cdf_[i] - (i ? cdf_[i - 1] : T(0))) / power_};
    }
    /// Light-sampling density (solid angle, light chosen by power) of the direction towards a
    /// point of area light `l` at squared distance r2, seen under cosine cos_l there.
    T pdf(const AreaLight<T>& l, T r2, T cos_l) const { return l.emission.luminance() / power_ * r2 / cos_l; }

private:
    std::vector<PolygonLight<T, 3>> lights_;
    std::vector<T> cdf_;
    T power_ = 0;
};

/// No next-event estimation of the area lights: the walk collects their emission wherever it
/// hits it, whole.
template <Scalar T = float>
struct BrdfOnlyDirect : NoPixelStatistics<T> {
    BrdfOnlyDirect() = default;
    BrdfOnlyDirect(const Scene<T>&, const PathTracerSettings<T>&) {}
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>&, S&, Q&, typename NoPixelStatistics<T>::vertex_record*) const {
        return Rgb<T>(T(0));
    }
    T emission_weight(const Arrival<T>&, const Ray<T>&, const StoreHit<T>&) const { return T(1); }
};

/// Light sampling and the BRDF sample combined by the balance heuristic (with sample counts:
/// k light samples and the one continuation ray, Veach and Guibas 1995).
template <Scalar T = float>
class MisDirect : public NoPixelStatistics<T> {
public:
    using vertex_record = typename NoPixelStatistics<T>::vertex_record;

    MisDirect(const Scene<T>& scene, const PathTracerSettings<T>& s)
        : scene_(&scene), lights_(scene), k_(std::max(1, s.light_samples)) {}

    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S& sampler, Q& queries, vertex_record*) const {
        Rgb<T> L(T(0));
        for (int i = 0; i < k_; ++i) L += light_sample(sp, sampler, queries);
        return L;
    }

    /// The BRDF sample's balance-heuristic weight where its ray meets area-light emission.
    T emission_weight(const Arrival<T>& from, const Ray<T>& ray, const StoreHit<T>& hit) const {
        if (!from.lights_sampled) return T(1);
        const T brdf_pdf = from.pdf;
        const std::int32_t li = scene_->light_of[hit.id];
        if (li < 0) return T(1);  // emissive but not a sampled light: only BRDF sampling finds it
        const auto& al = scene_->area_lights[std::size_t(li)];
        const T len2 = glm::dot(ray.direction, ray.direction);
        const T cos_l = -glm::dot(ray.direction, al.normal) / std::sqrt(len2);
        if (!(cos_l > T(0))) return T(0);
        const T pdf_light = lights_.pdf(al, hit.t * hit.t * len2, cos_l);
        return brdf_pdf / (brdf_pdf + T(k_) * pdf_light);
    }

private:
    /// One light sample (light by power, then uniform on it): f Le cos / (k p_light + p_brdf).
    template <class Q, class S>
        requires ShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> light_sample(const ShadingPoint<T>& sp, S& sampler, Q& queries) const {
        const T u_light = sampler.get_1d();
        const Vec2<T> u_point = sampler.get_2d();
        if (lights_.empty()) return Rgb<T>(T(0));
        const auto pick = lights_.pick(u_light);
        const auto& light = lights_.lights()[pick.index];
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
    SceneLights<T> lights_;
    int k_;
};

/// The environment map sampled by its importance (one sample per vertex) and by the BRDF
/// sample (the continuation ray), combined by the balance heuristic. In a scene without a map
/// it draws no samples and adds nothing (one predictable branch per vertex).
template <Scalar T = float>
class MisEnvironment {
public:
    MisEnvironment() = default;
    explicit MisEnvironment(const Scene<T>& scene) : env_(scene.environment ? &*scene.environment : nullptr) {}

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
    Rgb<T> escaped(const Vec3<T>& dir, const Arrival<T>& from) const {
        if (!env_) return Rgb<T>(T(0));
        const T w = from.lights_sampled ? balance_weight(from.pdf, env_->pdf(safe_normalize(dir))) : T(1);
        return env_->eval(dir) * w;
    }

private:
    const EnvironmentMap<T>* env_ = nullptr;
};

}  // namespace glint
