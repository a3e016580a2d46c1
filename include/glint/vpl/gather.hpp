// glint/vpl/gather.hpp: the gathering phase of the virtual light sources method at one point
// (Szécsi 2009, §1.4; Keller 1997): what a camera ray sees through mirrors and dielectrics,
// direct illumination from the real lights, and the VPLs' illumination through a visibility
// policy; and the same VPL sum over a fixed array of points (gather_image).
//
// A shading point x seen through a pixel (after any mirror or dielectric vertices, followed
// deterministically with a Fresnel choice) gets
//   L(x) = Le(x) + L_direct(x) + sum_vpl f_r(x, wi) dPhi (kd_y / pi) cos(theta_x) cos(theta_y) / |x - y|^2 V(x, y)
// where f_r(x) is the hit material's full BRDF (SurfaceBrdf) and the VPL reflects diffusely.
// L_direct samples the real lights (emitter by power, uniform on an area light; shadow rays
// through RayQueries). V(x, y) is a VisibilityPolicy (occluders/visibility.hpp): exact shadow
// rays (ShadowRayVisibility) or the occluder-sphere searches of Szécsi 2009, ch. 5
// (approximate). The VPL geometry term diverges as |x - y| -> 0; the usual clamp replaces
// |x - y|^2 by max(|x - y|^2, d_min^2) (VplSettings::min_distance; 0 = off; Kollig and Keller
// 2004 analyse the bias it leaves). Clamping only removes energy, so its bias is negative.
// The VPL sum is over every VPL (VplGather::all) or through a light cut (VplGather::cuts:
// lightcuts over the VPLs as cosine points, lights/cuts.hpp; deterministic and biased, each
// node's error bounded as that header says): VplLights holds the VPLs and, for cuts, their
// cluster tree, built once.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/parallel.hpp>
#include <glint/lights/cluster_tree.hpp>
#include <glint/lights/cuts.hpp>
#include <glint/lights/light_points.hpp>
#include <glint/occluders/visibility.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>
#include <glint/vpl/shooting.hpp>

namespace glint {

/// How the VPLs' illumination is summed: every VPL, or through a light cut.
enum class VplGather : std::uint8_t { all, cuts };

/// The VPL method's own settings; the image's (size, samples, threads) are the renderer's
/// RenderSettings.
struct VplSettings {
    std::size_t vpl_walks = 256; ///< shooting walks (each leaves a VPL per non-specular hit)
    double min_distance = 0;     ///< geometry-term clamp d_min, world units (0: unclamped, unbiased)
    int light_samples = 1;       ///< real-light samples per pixel for direct illumination (>= 1)
    bool direct = true;          ///< emission seen directly plus direct illumination
    bool indirect = true;        ///< the VPLs' illumination
    std::uint64_t seed = 1;      ///< shooting and the pixels' sampler streams
    ShootingOptions shooting{};  ///< Walk depth cap of the shooting phase.
    int max_specular = 16;       ///< mirror/dielectric vertices followed from the camera (>= 0)
    VplGather gather = VplGather::all;  ///< Sum over every VPL or through a light cut.
    CutSettings cut{};           ///< gather = cuts: the cut's threshold and largest size
    /// gather = cuts: the cluster tree's merge order. By orientation: a wall's VPLs share its
    /// normal, and clusters that keep to one orientation have tight bounds (docs/lights.md).
    ClusterGrouping grouping = ClusterGrouping::by_orientation;

    /// Throws Error for invalid cut settings, a negative or non-finite min_distance,
    /// light_samples < 1 or max_specular < 0.
    void validate() const {
        cut.validate();
        if (!(min_distance >= 0) || !std::isfinite(min_distance))
            throw Error("glint::VplSettings: min_distance " + std::to_string(min_distance) + " must be finite and >= 0");
        if (light_samples < 1) throw Error("glint::VplSettings: light_samples " + std::to_string(light_samples) + " < 1");
        if (max_specular < 0) throw Error("glint::VplSettings: max_specular " + std::to_string(max_specular) + " < 0");
    }
};

/// The first non-specular point seen along a camera ray, with the camera path's weight.
template <Scalar T>
struct PixelPoint {
    /// \var n
    /// Unit geometric normal at x, facing the viewer.

    /// Position, world space.
    Vec3<T> x{0}, n{0}, wo{0};  ///< Unit direction from x to the viewer (the previous path vertex).
    Rgb<T> weight{};            ///< product of the specular reflectances before x
    Rgb<T> emitted{};           ///< emission seen along the camera path (weighted)
    std::uint32_t material = 0;  ///< Index into Scene::materials of the material at x.
    std::uint32_t triangle = 0;  ///< the scene triangle at x, and x's barycentrics (u, v) on it
    /// Barycentric u of x on `triangle` (the hit's u).
    T u = 0, v = 0;  ///< Barycentric v of x on `triangle` (the hit's v).
    bool hit = false;  ///< False when the path left the scene or passed max_specular (x, n, wo, material, triangle, u, v unset).
};

/// A source of independent uniforms in [0, 1): a callable returning T (a sampler's get_1d, a
/// Pcg32 stream).
template <class U, class T>
concept UniformSource = std::invocable<U&> && std::convertible_to<std::invoke_result_t<U&>, T>;

/// Follows a camera ray through mirrors and dielectrics (at most max_specular of them; the
/// dielectrics' Fresnel choices drawn from `uniform`) to the first diffuse or glossy point.
template <class A, class U, Scalar T>
    requires UniformSource<U, T>
PixelPoint<T> surface_seen(const Scene<T>& s, RayQueries<A>& rays, Ray<T> ray, int max_specular, U&& uniform) {
    PixelPoint<T> p;
    p.weight = Rgb<T>(T(1));
    p.emitted = Rgb<T>(T(0));
    for (int k = 0; k <= max_specular; ++k) {
        StoreHit<T> hit;
        if (!rays.closest_hit(ray, hit)) return p;
        const Material<T>& m = s.materials[s.material_of[hit.id]];
        const Vec3<T> ng = s.normal(hit.id), d = safe_normalize(ray.direction);
        const bool front = glm::dot(ng, d) < T(0);
        const Vec3<T> x = ray.at(hit.t), n = front ? ng : -ng;
        if (front && m.emissive()) p.emitted += p.weight * m.emission;
        if (!m.specular()) {
            p.x = x, p.n = n, p.wo = -d, p.material = s.material_of[hit.id], p.hit = true;
            p.triangle = hit.id, p.u = hit.u, p.v = hit.v;
            return p;
        }
        p.weight *= specular_albedo(m);
        ray = detail::light_spawn(x, n, specular_direction(m, d, ng, T(uniform())));
    }
    return p;
}

/// Direct illumination at p from `samples` real-light samples (shadow rays through `rays`),
/// three uniforms each.
template <class A, class U, Scalar T>
    requires UniformSource<U, T>
Rgb<T> direct_light(const Scene<T>& s, RayQueries<A>& rays, const EmitterSet<T>& lights, const PixelPoint<T>& p,
                    int samples, U&& uniform) {
    const Frame<T> frame = Frame<T>::from_normal(p.n);
    const SurfaceBrdf<T> brdf(s.materials[p.material], frame.to_local(p.wo));
    Rgb<T> sum(T(0));
    for (int i = 0; i < samples; ++i) {
        T pdf;
        const T u = T(uniform());
        const T u0 = T(uniform());
        const LightSample<T> ls = lights.sample_point(u, Vec2<T>(u0, T(uniform())), pdf);
        const Vec3<T> d = ls.position - p.x;
        const T r2 = glm::dot(d, d);
        const Vec3<T> wi = d / std::sqrt(r2);
        const bool point = ls.normal == Vec3<T>(0);
        const T cos_l = point ? T(1) : -glm::dot(wi, ls.normal);
        const Vec3<T> wl = frame.to_local(wi);
        if (!(cos_l > T(0)) || wl.z <= T(0) || !(pdf > T(0))) continue;
        const Rgb<T> f = brdf.f(wl);
        if (f.max() <= T(0)) continue;
        const Ray<T> r0 = detail::light_spawn(p.x, p.n, wi);
        const Vec3<T> y = point ? ls.position : detail::light_spawn(ls.position, ls.normal, -wi).origin;
        if (!rays.unoccluded(Ray<T>{r0.origin, y - r0.origin, T(0), T(1) - T(1e-4)})) continue;
        sum += ls.towards(-wi) * f * (wl.z * cos_l / (r2 * pdf));
    }
    return sum * (p.weight / T(samples));
}

/// Sum over the VPLs of dPhi (kd_y / pi) w(wi) cos(theta_x) cos(theta_y) / max(r^2, d2min)
/// V(x, y) at point x (normal n), w(wi) = brdf(wi) (f_r for radiance, 1 for irradiance). The
/// VPLs go in blocks of 64: the ones that would contribute, then one batch visibility test
/// (visible_all: a stream of shadow rays for ShadowRayVisibility), then the sum in VPL order.
template <Scalar T, class V, class Brdf>
    requires VisibilityPolicy<V, T>
Rgb<T> vpl_sum(const Vec3<T>& x, const Vec3<T>& n, std::span<const Vpl<T>> vpls, V& vis, T d2min, const Brdf& brdf) {
    constexpr std::size_t block = 64;
    std::array<Vec3<T>, block> at;
    std::array<Rgb<T>, block> term;
    std::array<bool, block> seen;
    Rgb<T> sum(T(0));
    for (std::size_t b = 0; b < vpls.size(); b += block) {
        std::size_t k = 0;
        for (const Vpl<T>& v : vpls.subspan(b, std::min(block, vpls.size() - b))) {
            const Vec3<T> d = v.position - x;
            const T r2 = glm::dot(d, d);
            if (!(r2 > T(0))) continue;
            const Vec3<T> wi = d / std::sqrt(r2);
            const T cx = glm::dot(n, wi), cy = -glm::dot(v.normal, wi);
            if (cx <= T(0) || cy <= T(0)) continue;  // facing away: no contribution, no test
            const Rgb<T> f = brdf(wi);
            if (f.max() <= T(0)) continue;
            at[k] = v.position;
            term[k++] = v.power * v.albedo * f * (cx * cy / (std::max(r2, d2min) * pi<T>));
        }
        visible_all<T>(vis, std::span<const Vec3<T>>(at.data(), k), std::span<bool>(seen.data(), k));
        for (std::size_t i = 0; i < k; ++i)
            if (seen[i]) sum += term[i];
    }
    return sum;
}

/// Sum of the VPLs' illumination reflected at p towards the viewer (without p.weight),
/// visibility by policy `vis`; d2min is the squared clamp distance (0: unclamped).
template <Scalar T, class V>
    requires VisibilityPolicy<V, T>
Rgb<T> gather_point(const Scene<T>& s, const PixelPoint<T>& p, std::span<const Vpl<T>> vpls, V& vis, T d2min) {
    const Frame<T> frame = Frame<T>::from_normal(p.n);
    const SurfaceBrdf<T> brdf(s.materials[p.material], frame.to_local(p.wo));
    vis.set_point(p.x, p.n);
    return vpl_sum(p.x, p.n, vpls, vis, d2min, [&](const Vec3<T>& wi) { return brdf.f(frame.to_local(wi)); });
}

/// The VPLs a gather sums over: every one (VplGather::all), or through a cut of their cluster
/// tree (VplGather::cuts; the tree is built here, once). `vpls` must outlive it.
template <Scalar T>
class VplLights {
public:
    /// Views `vpls` (not copied) and, for VplGather::cuts, builds their cluster tree (allocates,
    /// O(n log n)). Throws Error for invalid cut settings.
    VplLights(std::span<const Vpl<T>> vpls, VplGather mode = VplGather::all, const CutSettings& cut = {},
              ClusterGrouping grouping = ClusterGrouping::by_orientation)
        : vpls_(vpls), cut_(cut), cuts_(mode == VplGather::cuts) {
        cut.validate();
        if (cuts_) tree_ = std::make_shared<const LightClusterTree<T>>(vpl_light_points<T>(vpls), grouping);
    }
    /// The same with the mode, cut settings and grouping of `st`.
    VplLights(std::span<const Vpl<T>> vpls, const VplSettings& st) : VplLights(vpls, st.gather, st.cut, st.grouping) {}

    /// The VPLs' illumination reflected at p towards the viewer (without p.weight).
    template <class V>
        requires VisibilityPolicy<V, T>
    Rgb<T> gather(const Scene<T>& s, const PixelPoint<T>& p, V& vis, T d2min) const {
        if (!cuts_) return gather_point(s, p, vpls_, vis, d2min);
        const Frame<T> frame = Frame<T>::from_normal(p.n);
        const SurfaceBrdf<T> brdf(s.materials[p.material], frame.to_local(p.wo));
        vis.set_point(p.x, p.n);
        const CutReceiver<T> r{p.x, p.n, frame, &brdf, d2min};
        return evaluate_cut(*tree_, r, cut_, [&](const PointLight<T>& l) { return vis.visible(l.position); }).L;
    }

    /// The VPLs given at construction.
    std::span<const Vpl<T>> vpls() const { return vpls_; }
    /// The cluster tree (null for VplGather::all).
    const LightClusterTree<T>* tree() const { return tree_.get(); }

private:
    std::span<const Vpl<T>> vpls_;
    CutSettings cut_;
    bool cuts_;
    std::shared_ptr<const LightClusterTree<T>> tree_;
};

/// The VPLs' illumination at fixed points (weighted by each point's camera path): the same
/// VPL sums at the same points many times over (one image per shooting path in light
/// animation, one per frame or walk count in light path maps' comparisons) with no camera ray
/// and no random number, which is why it is a loop of its own beside the Renderer. Blocks
/// of 64 points in parallel, one copy of the visibility policy per thread.
template <Scalar T, class V>
    requires VisibilityPolicy<V, T>
std::vector<Rgb<T>> gather_image(const Scene<T>& s, std::span<const PixelPoint<T>> points, std::span<const Vpl<T>> vpls,
                                 const V& visibility, double min_distance, int threads) {
    return gather_image(s, points, VplLights<T>(vpls), visibility, min_distance, threads);
}

/// The same through VplLights (every VPL, or a cut per point).
template <Scalar T, class V>
    requires VisibilityPolicy<V, T>
std::vector<Rgb<T>> gather_image(const Scene<T>& s, std::span<const PixelPoint<T>> points, const VplLights<T>& vpls,
                                 const V& visibility, double min_distance, int threads) {
    std::vector<Rgb<T>> out(points.size(), Rgb<T>(T(0)));
    const T d2min = T(min_distance * min_distance);
    const int blocks = int((points.size() + 63) / 64);
    detail::parallel_blocks(blocks, threads, [&](std::atomic<int>& next) {
        V vis = visibility;
        for (int b = next++; b < blocks; b = next++)
            for (std::size_t i = std::size_t(b) * 64; i < std::min(points.size(), std::size_t(b + 1) * 64); ++i)
                if (points[i].hit) out[i] = vpls.gather(s, points[i], vis, d2min) * points[i].weight;
    });
    return out;
}

}  // namespace glint
