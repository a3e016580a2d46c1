// glint/tracer/first_hit_layers.hpp: the layers a denoiser takes next to the image (Open
// Image Denoise's albedo and normal, and a depth layer), from each pixel's camera rays to
// their first hit.
//
// FirstHitLayers is an Integrator: under the same Renderer, camera, sampler and sample
// indices as the beauty pass, it traces the very rays the beauty pass starts with, so its
// layers are filtered by the same pixel filter (the box over each pixel's jittered samples,
// or the centre with RenderSettings::pixel_jitter off). Per camera ray:
//   albedo  the hit material's reflectance kd + ks, each band at most 1 (a Lambertian
//           surface's kd; a mirror's ks; a dielectric's 1); 0 where the ray misses;
//   normal  the hit triangle's unit geometric normal, turned toward the ray's origin (world
//           space); 0 where the ray misses (a pixel that straddles an edge averages normals,
//           so only pixels inside one plane have unit length);
//   depth   the distance from the camera to the hit (camera rays have unit directions),
//           averaged over the samples that hit; +infinity where none does.
// render_first_hit_named() renders them with the sampler a NamedRender names, as
// render_named() renders the beauty pass.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <span>
#include <variant>
#include <vector>

#include <glint/core/image.hpp>
#include <glint/core/math.hpp>
#include <glint/core/offset.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/tracer/any_accel.hpp>
#include <glint/tracer/named_render.hpp>
#include <glint/tracer/renderer.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// The first-hit layers of an image: albedo (RGB), normal (XYZ in R, G, B) and depth.
struct FirstHitImages {
    Image<Rgb<float>> albedo;  ///< The first hit's reflectance kd + ks, each band at most 1; 0 where rays miss.
    Image<Rgb<float>> normal;  ///< The mean unit geometric normal, turned toward the camera; 0 where rays miss.
    Image<float> depth;        ///< The mean distance from the camera to the hit; +inf where no ray hits.
};

/// The integrator whose radiance is the first hit's albedo, and which keeps each pixel's
/// summed normals and depths for finish(), which adds the layers "normal" and "depth" (grey).
template <RayAccelerator A>
class FirstHitLayers {
public:
    using scalar_type = typename A::scalar_type;  ///< The accelerator's float type.
    using T = scalar_type;                         ///< Short for scalar_type.
    /// One pixel's sums over its samples, for finish().
    struct pixel_state {
        Vec3<T> normal{0};         ///< Sum of the hits' normals (turned toward the camera).
        T depth = 0;               ///< Sum of the hits' distances from the camera.
        std::uint32_t samples = 0;  ///< Camera rays traced.
        std::uint32_t hits = 0;     ///< Camera rays that hit something.
    };

    /// Over `scene` traced through `accel` (both must outlive the integrator).
    FirstHitLayers(const Scene<T>& scene, const A& accel) : scene_(scene), accel_(accel) {}

    /// One camera ray: its first hit's albedo as the radiance (one ray traced); adds the
    /// hit's normal and depth to the pixel's state.
    template <class S>
    PathSample<T> radiance(const Ray<T>& ray, S&, pixel_state& state) const {
        PathSample<T> out;
        out.rays = 1;
        ++state.samples;
        StoreHit<T> hit;
        if (!accel_.closest_hit(ray, hit)) return out;
        Vec3<T> n = geometric_normal(scene_.triangles[hit.id]);
        if (glm::dot(n, ray.direction) > T(0)) n = -n;
        state.normal += n;
        state.depth += hit.t * glm::length(ray.direction);
        ++state.hits;
        const Material<T> m = scene_.material_at(hit.id, hit.u, hit.v);
        for (std::size_t c = 0; c < 3; ++c) out.L[c] = std::min(m.kd[c] + m.ks[c], T(1));
        return out;
    }

    /// Adds the film layers "normal" (RGB) and "depth" (grey) from the pixels' states.
    void finish(Film& film, std::span<const pixel_state> states) const {
        FilmLayer normal{"normal", Image<Rgb<float>>(film.image.width, film.image.height), false};
        FilmLayer depth{"depth", Image<Rgb<float>>(film.image.width, film.image.height), true};
        for (std::size_t i = 0; i < states.size(); ++i) {
            const pixel_state& s = states[i];
            const Vec3<T> n = s.samples > 0 ? s.normal / T(s.samples) : Vec3<T>(0);
            normal.pixels.pixels[i] = Rgb<float>(float(n.x), float(n.y), float(n.z));
            depth.pixels.pixels[i] =
                Rgb<float>(s.hits > 0 ? float(s.depth / T(s.hits)) : std::numeric_limits<float>::infinity());
        }
        film.layers.push_back(std::move(normal));
        film.layers.push_back(std::move(depth));
    }

private:
    const Scene<T>& scene_;
    const A& accel_;
};

/// The first-hit layers of `scene` through accelerator `accel` with the image settings and
/// the sampler that `o` names: the camera rays render_named(scene, accel, o) starts with.
template <Scalar T>
FirstHitImages render_first_hit_named(const Scene<T>& scene, const AnyAccel& accel, const NamedRender<T>& o) {
    const NamedChoices<T> names = resolve_names(o);
    const SamplerChoice<T> sampler = names.sampler(o.image.width, o.image.height, o.seed);
    const RenderResult r = std::visit(
        [&](const auto& s) { return render_image(scene, o.image, FirstHitLayers<AnyAccel>(scene, accel), s); }, sampler);
    FirstHitImages out{r.image, r.layer("normal")->pixels, Image<float>(r.image.width, r.image.height)};
    const Image<Rgb<float>>& depth = r.layer("depth")->pixels;
    for (std::size_t i = 0; i < depth.pixels.size(); ++i) out.depth.pixels[i] = depth.pixels[i][0];
    return out;
}

}  // namespace glint
