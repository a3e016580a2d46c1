// glint/lights/light_points.hpp: the many-light view of a scene: every emitter as a point
// light (lights/light.hpp), the input of the light cluster tree (lights/cluster_tree.hpp).
//
//   scene_light_points   the scene's point lights as themselves, and every polygon area light
//                        split into n stratified oriented points (cosine profile, intensity
//                        Le A / n along the light's normal): Fernandez 2004, §5.1, "area lights
//                        become subtrees of oriented points". n per light comes from a spacing
//                        (one point per spacing^2 of area) or from a target total (shared out
//                        by area); the points are the 2-D Hammersley set (i + 1/2) / n, radical
//                        inverse base 2, mapped onto the polygon's fan of triangles.
//   vpl_light_points     virtual point lights (vpl/shooting.hpp's position, normal, power,
//                        albedo) as cosine points of intensity power albedo / pi: the term
//                        vpl/gather.hpp's vpl_sum evaluates (dPhi kd / pi cos_y).
// Splitting an area light is an approximation: the sum over its points converges to the
// polygon's illumination as n grows (the error is largest close to the light).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/lights/light.hpp>
#include <glint/sampling/radical_inverse.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// Which of a scene's emitters become points, and how finely area lights are split.
template <Scalar T>
struct LightPointOptions {
    bool point_lights = true;   ///< The scene's point lights, as themselves.
    bool area_lights = true;    ///< Its polygon area lights, split into oriented points.
    std::size_t total = 4096;   ///< Area-light points in all (shared out by area), when spacing is 0.
    T spacing = T(0);           ///< > 0: one point per spacing^2 of area instead (world units).
    std::size_t max_per_light = std::size_t(1) << 20;  ///< Most points one area light becomes; > 0.

    /// Throws Error for a negative or non-finite spacing, total 0 when area lights are split by
    /// count, or max_per_light 0.
    void validate() const {
        if (!(spacing >= T(0)) || !std::isfinite(double(spacing)))
            throw Error("glint::LightPointOptions: spacing " + std::to_string(double(spacing)) + " must be finite and >= 0");
        if (area_lights && spacing == T(0) && total == 0)
            throw Error("glint::LightPointOptions: total must be positive when area lights are split by count");
        if (max_per_light == 0) throw Error("glint::LightPointOptions: max_per_light must be positive");
    }
};

/// How many points area light `l` becomes: from the spacing, or its share (by area) of
/// `total`; at least 1.
template <Scalar T>
std::size_t area_light_points(const AreaLight<T>& l, T total_area, const LightPointOptions<T>& o) {
    double n = o.spacing > T(0) ? double(l.area) / (double(o.spacing) * double(o.spacing))
                                : double(o.total) * double(l.area) / double(total_area);
    n = std::clamp(std::round(n), 1.0, double(o.max_per_light));
    return std::size_t(n);
}

/// Appends n stratified oriented points of area light `l` to `out`.
template <Scalar T>
void split_area_light(const AreaLight<T>& l, std::size_t n, std::vector<PointLight<T>>& out) {
    const PolygonSampler<T> polygon(std::span<const Vec3<T>>(l.vertices));
    const Rgb<T> intensity = l.emission * (l.area / T(n));
    for (std::size_t i = 0; i < n; ++i) {
        const Vec2<T> u((T(i) + T(0.5)) / T(n), radical_inverse<T>(2, i));
        out.push_back(PointLight<T>::oriented(polygon.sample(u), l.normal, intensity));
    }
}

/// The scene's emitters as point lights: its point lights first (in order), then each area
/// light's points (area light by area light).
template <Scalar T>
std::vector<PointLight<T>> scene_light_points(const Scene<T>& s, const LightPointOptions<T>& o = {}) {
    o.validate();
    std::vector<PointLight<T>> out;
    if (o.point_lights) {
        for (std::size_t i = 0; i < s.point_lights.size(); ++i) s.point_lights[i].validate(i);
        out.assign(s.point_lights.begin(), s.point_lights.end());
    }
    if (!o.area_lights) return out;
    T area = T(0);
    for (const auto& l : s.area_lights) area += l.area;
    for (const auto& l : s.area_lights) split_area_light(l, area_light_points(l, area, o), out);
    return out;
}

/// Virtual point lights as cosine points of intensity power albedo / pi along their normal.
template <Scalar T, class V>
std::vector<PointLight<T>> vpl_light_points(std::span<const V> vpls) {
    std::vector<PointLight<T>> out;
    out.reserve(vpls.size());
    for (const V& v : vpls) out.push_back(PointLight<T>::oriented(v.position, v.normal, v.power * v.albedo / pi<T>));
    return out;
}

}  // namespace glint
