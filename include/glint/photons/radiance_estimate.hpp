// glint/photons/radiance_estimate.hpp: the photon map's density estimate (Jensen 2001, ch. 7,
// Larsen 2004, §4.3, eq. 4.2) and its precomputed form at every 4th photon
// (Christensen 1999; Larsen 2004, §4.6.1).
//
// Reflected radiance at x (normal n) towards the viewer, from the k nearest photons p:
//   L(x, w) ~ sum_p f_r(x, w_p, w) Phi_p w_p / (c pi r^2),
// r the distance to the farthest photon found (max_radius when fewer than k were found: the
// disc the search covered), w_p = -(the photon's direction) and only photons arriving from
// n's side counted. Filters (Jensen 2001, ch. 7): `none` (w_p = c = 1) or `cone`, w_p = 1 -
// d_p / (k_c r), c = 1 - 2 / (3 k_c) (k_c >= 1), which weights near photons more and blurs
// less at edges. The estimate is biased (it averages over the disc, and r is set by the
// photons themselves); it is consistent as the photons grow and r shrinks.
//
// Precomputed irradiance (Christensen 1999): the irradiance E = the sum above with f_r = 1
// is computed once at every `stride`-th photon of the map (heap order; 4 in Larsen 2004) with
// the photon's own normal; a lookup returns E of the nearest such photon within a radius
// whose normal is within acos(min_cos) of the query's (0.9 by default), or zero. Radiance of
// a diffuse surface is then kd / pi E.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/parallel.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/photons/photon_map.hpp>

namespace glint {

/// How found photons are weighted: equally, or by Jensen 2001's cone filter (ch. 7).
enum class PhotonFilter : std::uint8_t { none, cone };

/// The radiance estimate's knobs: photons per estimate, radius bound and filter.
struct RadianceEstimateSettings {
    std::size_t k = 100;       ///< Photons per estimate; > 0.
    float max_radius = 0.1f;   ///< Search radius bound (scene units); > 0.
    PhotonFilter filter = PhotonFilter::none;  ///< Equal weights or the cone filter.
    float cone_k = 1.0f;       ///< k_c of the cone filter, >= 1.

    /// Throws Error for k = 0, a max_radius that is not positive, or cone_k < 1.
    void validate() const {
        if (k == 0) throw Error("glint::RadianceEstimateSettings: k must be positive (got 0)");
        if (!(max_radius > 0.0f)) throw Error("glint::RadianceEstimateSettings: max_radius must be positive (got " + std::to_string(max_radius) + ")");
        if (!(cone_k >= 1.0f)) throw Error("glint::RadianceEstimateSettings: cone_k must be >= 1 (got " + std::to_string(cone_k) + ")");
    }
};

/// sum_p f(w_p) Phi_p w_p / (c pi r^2) over the k nearest photons to x arriving from n's
/// side; f(const Vec3<float>& w_p) -> Rgb<float> is the BRDF towards the viewer for light
/// from w_p (world space, pointing away from the surface). `scratch` holds the found photons.
template <class Brdf>
Rgb<float> radiance_estimate(const PhotonMap& map, const Vec3<float>& x, const Vec3<float>& n, const Brdf& f,
                             const RadianceEstimateSettings& s, std::vector<PhotonNeighbour>& scratch) {
    map.knn(x, s.k, s.max_radius, scratch);
    if (scratch.empty()) return Rgb<float>(0.0f);
    const float r2 = scratch.size() == s.k ? scratch.front().d2 : s.max_radius * s.max_radius;
    if (!(r2 > 0.0f)) return Rgb<float>(0.0f);
    const bool cone = s.filter == PhotonFilter::cone;
    const float inv_kr = cone ? 1.0f / (s.cone_k * std::sqrt(r2)) : 0.0f;
    Rgb<float> sum(0.0f);
    for (const PhotonNeighbour& q : scratch) {
        const Photon& p = map.photon(q.index);
        const Vec3<float> wp = -p.direction();
        if (glm::dot(wp, n) <= 0.0f) continue;
        const float w = cone ? std::max(0.0f, 1.0f - std::sqrt(q.d2) * inv_kr) : 1.0f;
        sum += f(wp) * p.power() * w;
    }
    const float c = cone ? 1.0f - 2.0f / (3.0f * s.cone_k) : 1.0f;
    return sum / (c * pi<float> * r2);
}

/// Irradiance at x (normal n): radiance_estimate with f = 1.
inline Rgb<float> irradiance_estimate(const PhotonMap& map, const Vec3<float>& x, const Vec3<float>& n,
                                      const RadianceEstimateSettings& s, std::vector<PhotonNeighbour>& scratch) {
    return radiance_estimate(map, x, n, [](const Vec3<float>&) { return Rgb<float>(1.0f); }, s, scratch);
}

/// Irradiance precomputed at every `stride`-th photon of a map (see the header comment).
class PrecomputedIrradiance {
public:
    PrecomputedIrradiance() = default;
    /// Estimates the irradiance at photons 0, stride, 2 stride, ... of `map` with settings s, on
    /// `threads` threads (0: hardware concurrency); throws Error for invalid s or stride 0.
    PrecomputedIrradiance(const PhotonMap& map, const RadianceEstimateSettings& s, int threads = 0, std::size_t stride = 4)
        : stride_(stride) {
        s.validate();
        if (stride == 0) throw Error("glint::PrecomputedIrradiance: stride must be positive (got 0)");
        const std::size_t count = (map.size() + stride - 1) / stride;
        values_.resize(count);
        normals_.resize(count);
        constexpr std::size_t block = 1024;
        const int blocks = int((count + block - 1) / block);
        detail::parallel_blocks(blocks, threads, [&](std::atomic<int>& next) {
            std::vector<PhotonNeighbour> scratch;
            for (int b = next++; b < blocks; b = next++)
                for (std::size_t j = std::size_t(b) * block; j < std::min(count, std::size_t(b + 1) * block); ++j) {
                    const Photon& p = map.photon(j * stride);
                    normals_[j] = p.normal();
                    values_[j] = irradiance_estimate(map, p.position, normals_[j], s, scratch);
                }
        });
    }

    /// Number of precomputed values: ceil(map size / stride).
    std::size_t size() const { return values_.size(); }
    /// Every stride-th photon carries a value.
    std::size_t stride() const { return stride_; }

    /// E of the nearest precomputed photon within max_radius of x whose normal has cosine
    /// >= min_cos with n; zero where there is none. `map` is the map it was built from.
    Rgb<float> lookup(const PhotonMap& map, const Vec3<float>& x, const Vec3<float>& n, float max_radius,
                      std::vector<PhotonNeighbour>& scratch, float min_cos = 0.9f) const {
        map.nearest(x, 1, max_radius, scratch, [&](std::uint32_t i) {
            return i % stride_ == 0 && glm::dot(normals_[i / stride_], n) >= min_cos;
        });
        return scratch.empty() ? Rgb<float>(0.0f) : values_[scratch.front().index / stride_];
    }

private:
    std::size_t stride_ = 4;
    std::vector<Rgb<float>> values_;
    std::vector<Vec3<float>> normals_;
};

}  // namespace glint
