// glint/photons/photon_tracing.hpp: the first pass of photon mapping (Jensen 2001, ch. 5;
// Larsen 2004, §4.2): photons emitted from the scene's lights in proportion to their power,
// traced through every material, stored where they hit a non-specular surface.
//
// Emission: an emitter (an emissive triangle, Phi = pi Le A, or a point light, Phi =
// PointLight::power()) is chosen with probability P_k proportional to the luminance of its
// power; an area light's photon leaves a uniform point in a cosine-distributed direction, a
// point light's in a uniform direction through the light's profile (power 4 pi I(w) / P_k).
// Photon i draws its numbers from its own PCG stream Pcg32::hashed(seed, i), so a photon set
// is the same for any thread count; with PhotonEmission::halton its five emission numbers
// (emitter, position, direction) are instead point i + 1 of the Halton sequence in bases 2,
// 3, 5, 7, 11 (Larsen 2004, ch. 6: quasi-random emission), rotated by one random shift per
// dimension drawn from the seed (Cranley-Patterson), and only the walk after emission uses
// the PCG stream. Stored powers already carry the 1 / emitted of the
// estimator: their sum estimates the power arriving at the scene's surfaces.
//
// Transport: at a mirror or dielectric the photon follows specular_direction (Fresnel choice
// for a dielectric); at any other surface it is stored and then scattered by the material's
// own BRDF (SurfaceBrdf: Lambertian and Phong lobes). Russian roulette on the albedo
// (Jensen 2001, ch. 5; the classic rule of sampling/roulette.hpp: continue with probability
// luminance(albedo), power times albedo / probability), so that in a grey scene every photon
// keeps the power it was emitted with.
//
// Maps: a photon whose path is L S+ D (one or more specular vertices, then the first
// non-specular one) goes to `caustic`; every other stored photon to `global`, including,
// when PhotonSettings::store_direct is set (the default), the first hit of direct light
// (Jensen 2001, ch. 9: the global map is what a final gather reads at its secondary hits).
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/parallel.hpp>
#include <glint/core/random.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/photons/photon.hpp>
#include <glint/sampling/primes.hpp>
#include <glint/sampling/radical_inverse.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/light_walk.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// Where a photon's emission numbers come from (see the header comment).
enum class PhotonEmission : std::uint8_t { random, halton };

/// How photons are traced: count, seed, depth cap, threads, direct hits, emission numbers.
struct PhotonSettings {
    std::size_t photons = 100000;  ///< Emitted photons; > 0.
    std::uint64_t seed = 1;        ///< Seeds each photon's PCG stream (and the Halton shifts).
    int max_depth = 64;            ///< Cap on a photon's vertices (roulette ends walks long before); >= 1.
    int threads = 0;               ///< 0: hardware concurrency.
    bool store_direct = true;      ///< The first hit of direct light goes to the global map.
    PhotonEmission emission = PhotonEmission::random;  ///< Where the five emission numbers come from.
};

/// The photons one tracing stored, split into the global and caustic maps' photons.
struct PhotonSet {
    /// Photons for the global map: every stored photon not on an L S+ D path.
    std::vector<Photon> global, caustic;  ///< Photons for the caustic map: first non-specular hit after specular vertices.
    std::size_t emitted = 0;  ///< Photons emitted (the powers already carry 1 / emitted).
    /// The scene triangle each photon of `global` and `caustic` lies on (parallel arrays):
    /// what one map per surface group (photons/surface_groups.hpp) sorts photons by.
    std::vector<std::uint32_t> global_triangle, caustic_triangle;  ///< The triangle of each photon of `caustic`, parallel to it.
};

/// Appends p's photons (both maps, with their triangles) to out's; `emitted` is left alone.
inline void append_photons(PhotonSet& out, const PhotonSet& p) {
    out.global.insert(out.global.end(), p.global.begin(), p.global.end());
    out.caustic.insert(out.caustic.end(), p.caustic.begin(), p.caustic.end());
    out.global_triangle.insert(out.global_triangle.end(), p.global_triangle.begin(), p.global_triangle.end());
    out.caustic_triangle.insert(out.caustic_triangle.end(), p.caustic_triangle.begin(), p.caustic_triangle.end());
}

/// The scene's emitters chosen by luminance power (emissive triangles, point lights).
template <Scalar T>
class PhotonEmitters {
public:
    /// The emitters of s (validated first); throws Error when no light emits.
    explicit PhotonEmitters(const Scene<T>& s) {
        s.validate();
        for (std::size_t i = 0; i < s.triangles.size(); ++i) {
            const Material<T>& m = s.materials[s.material_of[i]];
            const auto& t = s.triangles[i];
            const T a = triangle_area(t[0], t[1], t[2]);
            if (m.emissive() && a > T(0)) push(std::uint32_t(i), false, m.emission * (pi<T> * a));
        }
        for (std::size_t i = 0; i < s.point_lights.size(); ++i)
            if (s.point_lights[i].intensity.max() > T(0)) push(std::uint32_t(i), true, s.point_lights[i].power());
        if (cdf_.empty() || !(cdf_.back() > T(0)))
            throw Error("glint::trace_photons: scene '" + s.name + "' has no light that emits");
    }

    /// Total power of the emitters, per band.
    const Rgb<T>& power() const { return power_; }

    /// The ray photon leaves on from uniforms u[0..4], with the power it carries (not yet
    /// divided by the number of photons).
    Ray<T> emit(const Scene<T>& s, const std::array<T, 5>& u, Rgb<T>& power) const {
        const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u[0] * cdf_.back());
        const std::size_t k = std::min<std::size_t>(std::size_t(it - cdf_.begin()), cdf_.size() - 1);
        const T p = (cdf_[k] - (k ? cdf_[k - 1] : T(0))) / cdf_.back();
        const Source& e = sources_[k];
        if (e.point) {
            const PointLight<T>& l = s.point_lights[e.index];
            const Vec3<T> d = square_to_uniform_sphere(Vec2<T>(u[3], u[4]));
            power = l.intensity_towards(d) * (T(4) * pi<T> / p);
            return Ray<T>{l.position, d, T(0), infinity<T>};
        }
        const auto& t = s.triangles[e.index];
        const Vec3<T> n = s.normal(e.index);
        const Vec3<T> x = sample_triangle(t[0], t[1], t[2], Vec2<T>(u[1], u[2]));
        const Vec3<T> d = Frame<T>::from_normal(n).to_world(square_to_cosine_hemisphere(Vec2<T>(u[3], u[4])));
        power = e.power / p;
        return detail::light_spawn(x, n, d);
    }

private:
    struct Source {
        std::uint32_t index;
        bool point;
        Rgb<T> power;
    };
    void push(std::uint32_t i, bool point, const Rgb<T>& phi) {
        sources_.push_back({i, point, phi});
        power_ += phi;
        cdf_.push_back((cdf_.empty() ? T(0) : cdf_.back()) + phi.luminance());
    }
    std::vector<Source> sources_;
    std::vector<T> cdf_;
    Rgb<T> power_{T(0)};
};

/// Traces photon `index` of a set of `settings.photons` (its own stream), appending what it
/// stores to out's maps (and their triangles).
template <RayAccelerator A, Scalar T = typename A::scalar_type>
void trace_photon(const Scene<T>& s, const A& accel, const PhotonEmitters<T>& emitters, const PhotonSettings& settings,
                  std::uint64_t index, PhotonSet& out) {
    Pcg32 rng = Pcg32::hashed(settings.seed, index);
    std::array<T, 5> u{};
    if (settings.emission == PhotonEmission::halton) {
        Pcg32 shifts = Pcg32::hashed(settings.seed, ~std::uint64_t(0));  // the same for every photon
        for (std::size_t k = 0; k < u.size(); ++k)
            u[k] = fraction_to_unit<T>(radical_inverse_bits(primes[k], index + 1) + shifts.next_u64());
    } else {
        for (T& v : u) v = rng.uniform<T>();
    }
    Rgb<T> power;
    Ray<T> ray = emitters.emit(s, u, power);
    power /= T(settings.photons);
    light_walk(s, accel, Roulette<T, 3>::classic(), ray, power, rng, settings.max_depth, 0, [&](const LightWalkVertex<T>& v) {
        if (v.first && !v.via_specular && !settings.store_direct) return;
        const Photon photon{Vec3<float>(v.x), Rgb<float>(float(v.power[0]), float(v.power[1]), float(v.power[2])),
                            Vec3<float>(v.direction), Vec3<float>(v.n)};
        const bool caustic = v.first && v.via_specular;
        (caustic ? out.caustic : out.global).push_back(photon);
        (caustic ? out.caustic_triangle : out.global_triangle).push_back(v.triangle);
    });
}

/// Emits settings.photons photons and traces them (see the header comment), on
/// settings.threads threads in blocks of photon indices; the result does not depend on the
/// thread count.
template <RayAccelerator A, Scalar T = typename A::scalar_type>
PhotonSet trace_photons(const Scene<T>& s, const A& accel, const PhotonSettings& settings) {
    if (settings.photons == 0) throw Error("glint::trace_photons: photons must be positive (got 0)");
    if (settings.max_depth < 1)
        throw Error("glint::trace_photons: max_depth must be at least 1 (got " + std::to_string(settings.max_depth) + ")");
    const PhotonEmitters<T> emitters(s);
    constexpr std::size_t block = 4096;
    const std::size_t blocks = (settings.photons + block - 1) / block;
    std::vector<PhotonSet> parts(blocks);
    detail::parallel_blocks(int(blocks), settings.threads, [&](std::atomic<int>& next) {
        for (int b = next++; b < int(blocks); b = next++) {
            const std::size_t end = std::min(settings.photons, std::size_t(b + 1) * block);
            for (std::size_t i = std::size_t(b) * block; i < end; ++i)
                trace_photon(s, accel, emitters, settings, i, parts[std::size_t(b)]);
        }
    });
    PhotonSet out;
    out.emitted = settings.photons;
    for (const PhotonSet& p : parts) append_photons(out, p);
    return out;
}

}  // namespace glint
