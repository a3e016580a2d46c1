// glint/photons/texel_cache.hpp: texel caches of a scene's illumination (Larsen 2004, ch. 10 and
// 11): per texel, the approximated illumination (Larsen's AIM: the radiance a Lambertian
// surface reflects, kd / pi times the irradiance estimate from its surface group's photon
// map) and the indirect illumination (his IIM: the irradiance a final gather onto an enlarged
// hemicube's front plane, photons/hemiplane.hpp, collects from the other texels' AIMs).
//
// Texels: every triangle is cut into n^2 congruent sub-triangles (n = ceil(longest edge /
// texel_size)); a texel is one of them, its value held at its centroid and constant over it.
// A texel's position follows its triangle, so triangles may move (count and order fixed).
// Side: a texel faces the side of its triangle from which more photon power arrives (the
// estimate is made for both normals); gathers leave on that side.
//
// Priorities (Larsen 2004, §10.1 and §11.1): every photon stored or removed on a surface group
// adds its luminance to the group's delta_f, and, if it was reflected diffusely before it was
// stored, to delta_i. update() recomputes the AIMs of at most `groups_per_frame` groups whose
// delta_f / area exceeds `threshold`, largest first, and then gathers at most
// `texels_per_frame` texels' IIMs, taking the texels of the group of largest delta_i / area
// first; a group's delta is cleared when all its texels are done. update_all() recomputes
// everything. Only the diffuse part kd of a material is reconstructed; specular surfaces reflect
// nothing into the caches (gathers do not follow mirrors), emitters' emission is not gathered
// (direct light is the renderer's).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/parallel.hpp>
#include <glint/photons/hemiplane.hpp>
#include <glint/photons/photon_tracing.hpp>
#include <glint/photons/radiance_estimate.hpp>
#include <glint/photons/selective_tracing.hpp>
#include <glint/photons/surface_groups.hpp>

namespace glint {

/// The texel caches' knobs: texel size, the AIM's estimate, the IIM's gather plane, frame budgets.
struct TexelCacheSettings {
    float texel_size = 0.25f;                 ///< Target texel edge (world units); > 0.
    RadianceEstimateSettings estimate{50, 0.5f};  ///< The AIM's irradiance estimate (50 photons within 0.5).
    int hemiplane_resolution = 16;            ///< R: R x R gather rays a texel, in [1, 4096].
    float hemiplane_extent = 2.0f;            ///< a: the front face enlarged to twice its side; > 0.
    std::size_t groups_per_frame = 4;         ///< AIM updates (whole groups) per frame.
    std::size_t texels_per_frame = 20;        ///< IIM updates per frame.
    float threshold = 0.0f;                   ///< On delta / group area: a group at or below it is not updated; >= 0.
    int threads = 0;                          ///< Update threads (0: hardware concurrency).

    /// Throws Error for invalid estimate settings, a texel_size that is not positive and
    /// finite, or a negative threshold (the plane's own checks run when a cache is built).
    void validate() const {
        estimate.validate();
        if (!(texel_size > 0.0f) || !std::isfinite(texel_size))
            throw Error("glint::TexelCache: texel_size must be positive (got " + std::to_string(texel_size) + ")");
        if (!(threshold >= 0.0f)) throw Error("glint::TexelCache: threshold must be non-negative");
    }
};

/// What one budgeted update did.
struct TexelUpdate {
    std::size_t aim_groups = 0, aim_texels = 0, iim_texels = 0;
    /// \var aim_groups
    /// Surface groups whose AIMs were recomputed.
    /// \var aim_texels
    /// Texels of those groups (AIMs recomputed).
    /// \var iim_texels
    /// Texels whose IIM was gathered.
};

/// Texel caches of approximated (AIM) and indirect (IIM) illumination over a scene's
/// triangles (Larsen 2004, ch. 10-11), updated within a per-frame budget.
template <Scalar T>
class TexelCache {
public:
    /// Texels over the triangles of s, grouped by `groups` (one entry per triangle); throws
    /// Error for invalid settings or a grouping of another triangle count. Values start at 0.
    TexelCache(const Scene<T>& s, SurfaceGroups groups, const TexelCacheSettings& settings)
        : settings_(settings), groups_(std::move(groups)),
          plane_(settings.hemiplane_resolution, T(settings.hemiplane_extent)) {
        settings_.validate();
        s.validate();
        if (groups_.group_of.size() != s.triangles.size())
            throw Error("glint::TexelCache: " + std::to_string(groups_.group_of.size()) + " grouped triangles, scene has " +
                        std::to_string(s.triangles.size()));
        layout(s);
        delta_f_.assign(groups_.count, 0.0f);
        delta_i_.assign(groups_.count, 0.0f);
        cursor_.assign(groups_.count, 0);
    }

    /// Number of texels over all triangles.
    std::size_t texels() const { return texels_.size(); }
    /// The gather plane the IIMs are collected through.
    const HemiPlane<T>& plane() const { return plane_; }

    /// Adds a selective-tracing frame's removed and added photons to the groups' deltas.
    void record(const SelectiveFrame& f) {
        for (const auto* list : {&f.removed, &f.added})
            for (const PhotonChange& c : *list) {
                delta_f_[groups_.group_of[c.triangle]] += c.luminance;
                if (c.bounced) delta_i_[groups_.group_of[c.triangle]] += c.luminance;
            }
    }

    /// Recomputes every texel's AIM and then IIM from `photons` (global map) in scene s.
    template <RayAccelerator A>
    void update_all(const Scene<T>& s, const A& accel, const PhotonSet& photons) {
        std::vector<std::uint32_t> all(groups_.count);
        std::iota(all.begin(), all.end(), 0u);
        update_aims(s, photons, all);
        std::vector<std::uint32_t> every(texels_.size());
        std::iota(every.begin(), every.end(), 0u);
        gather(s, accel, every);
        std::fill(delta_f_.begin(), delta_f_.end(), 0.0f);
        std::fill(delta_i_.begin(), delta_i_.end(), 0.0f);
        std::fill(cursor_.begin(), cursor_.end(), 0);
    }

    /// The budgeted update (see the header comment).
    template <RayAccelerator A>
    TexelUpdate update(const Scene<T>& s, const A& accel, const PhotonSet& photons) {
        TexelUpdate out;
        std::vector<std::uint32_t> aim = by_priority(delta_f_);
        if (aim.size() > settings_.groups_per_frame) aim.resize(settings_.groups_per_frame);
        out.aim_groups = aim.size();
        for (std::uint32_t g : aim) out.aim_texels += by_group_[g].size(), delta_f_[g] = 0.0f;
        update_aims(s, photons, aim);
        std::vector<std::uint32_t> chosen;
        for (std::uint32_t g : by_priority(delta_i_)) {
            const std::vector<std::uint32_t>& mine = by_group_[g];
            while (cursor_[g] < mine.size() && chosen.size() < settings_.texels_per_frame) chosen.push_back(mine[cursor_[g]++]);
            if (cursor_[g] < mine.size()) break;
            cursor_[g] = 0;
            delta_i_[g] = 0.0f;
        }
        gather(s, accel, chosen);
        out.iim_texels = chosen.size();
        return out;
    }

    /// AIM: radiance the diffuse surface reflects at x on `triangle` (the texel holding x).
    Rgb<T> approximated(const Scene<T>& s, std::uint32_t triangle, const Vec3<T>& x) const {
        return aim_[texel_at(s, triangle, x)];
    }
    /// IIM: indirect irradiance at x on `triangle`.
    Rgb<T> indirect(const Scene<T>& s, std::uint32_t triangle, const Vec3<T>& x) const {
        return iim_[texel_at(s, triangle, x)];
    }

private:
    struct Texel {
        std::uint32_t triangle;
        T b1, b2;   // centroid's barycentrics (weights of vertices 1 and 2)
        T side;     // +1 or -1: the triangle normal's sign the texel faces
    };
    struct Tiling {
        std::uint32_t n, first_cell;
    };

    void layout(const Scene<T>& s) {
        by_group_.assign(groups_.count, {});
        area_.assign(groups_.count, 0.0f);
        for (std::uint32_t t = 0; t < s.triangles.size(); ++t) {
            const auto& v = s.triangles[t];
            const T e = std::max({glm::length(v[1] - v[0]), glm::length(v[2] - v[1]), glm::length(v[0] - v[2])});
            const auto n = std::uint32_t(std::clamp(std::ceil(e / T(settings_.texel_size)), T(1), T(256)));
            tiling_.push_back({n, std::uint32_t(cell_.size())});
            area_[groups_.group_of[t]] += float(triangle_area(v[0], v[1], v[2]));
            cell_.resize(cell_.size() + 2 * std::size_t(n) * n, 0);
            for (std::uint32_t i = 0; i < n; ++i)
                for (std::uint32_t j = 0; i + j < n; ++j)
                    for (std::uint32_t up = 0; up < (i + j + 1 < n ? 2u : 1u); ++up) {
                        const T o = up ? T(2) / T(3) : T(1) / T(3);
                        cell_[tiling_[t].first_cell + (i * n + j) * 2 + up] = std::uint32_t(texels_.size());
                        by_group_[groups_.group_of[t]].push_back(std::uint32_t(texels_.size()));
                        texels_.push_back({t, (T(i) + o) / T(n), (T(j) + o) / T(n), T(1)});
                    }
        }
        aim_.assign(texels_.size(), Rgb<T>(T(0)));
        iim_.assign(texels_.size(), Rgb<T>(T(0)));
    }

    std::uint32_t texel_at(const Scene<T>& s, std::uint32_t triangle, const Vec3<T>& x) const {
        const auto& v = s.triangles[triangle];
        const Vec3<T> e1 = v[1] - v[0], e2 = v[2] - v[0], d = x - v[0];
        const T a = glm::dot(e1, e1), b = glm::dot(e1, e2), c = glm::dot(e2, e2), p = glm::dot(d, e1), q = glm::dot(d, e2);
        const T det = a * c - b * b;
        const T b1 = det > T(0) ? (c * p - b * q) / det : T(0), b2 = det > T(0) ? (a * q - b * p) / det : T(0);
        const Tiling& tl = tiling_[triangle];
        const T n = T(tl.n);
        const auto i = std::uint32_t(std::clamp(std::floor(b1 * n), T(0), n - T(1)));
        const auto j = std::uint32_t(std::clamp(std::floor(b2 * n), T(0), n - T(1 + i)));
        const bool up = i + j + 1 < tl.n && (b1 * n - T(i)) + (b2 * n - T(j)) > T(1);
        return cell_[tl.first_cell + (i * tl.n + j) * 2 + (up ? 1 : 0)];
    }

    Vec3<T> position(const Scene<T>& s, const Texel& x) const {
        const auto& v = s.triangles[x.triangle];
        return v[0] + (v[1] - v[0]) * x.b1 + (v[2] - v[0]) * x.b2;
    }

    std::vector<std::uint32_t> by_priority(const std::vector<float>& delta) const {
        std::vector<std::uint32_t> out;
        for (std::uint32_t g = 0; g < delta.size(); ++g)
            if (delta[g] > 0.0f && delta[g] / area_of(g) > settings_.threshold) out.push_back(g);
        std::stable_sort(out.begin(), out.end(), [&](std::uint32_t a, std::uint32_t b) {
            return delta[a] / area_of(a) > delta[b] / area_of(b);
        });
        return out;
    }

    float area_of(std::uint32_t g) const { return std::max(area_[g], 1e-20f); }

    /// AIMs of the listed groups, each from a map of its own photons, both sides estimated.
    void update_aims(const Scene<T>& s, const PhotonSet& photons, const std::vector<std::uint32_t>& groups) {
        std::vector<int> slot(groups_.count, -1);
        for (std::size_t k = 0; k < groups.size(); ++k) slot[groups[k]] = int(k);
        std::vector<std::vector<Photon>> parts(groups.size());
        for (std::size_t p = 0; p < photons.global.size(); ++p)
            if (const int k = slot[groups_.group_of[photons.global_triangle[p]]]; k >= 0) parts[std::size_t(k)].push_back(photons.global[p]);
        detail::parallel_blocks(int(groups.size()), settings_.threads, [&](std::atomic<int>& next) {
            std::vector<PhotonNeighbour> scratch;
            for (int k = next++; k < int(groups.size()); k = next++) {
                const PhotonMap map(std::move(parts[std::size_t(k)]));
                for (std::uint32_t id : by_group_[groups[std::size_t(k)]]) aim_texel(s, map, texels_[id], aim_[id], scratch);
            }
        });
    }

    void aim_texel(const Scene<T>& s, const PhotonMap& map, Texel& x, Rgb<T>& out, std::vector<PhotonNeighbour>& scratch) const {
        const Vec3<float> p(position(s, x)), n(s.normal(x.triangle));
        const Rgb<float> front = irradiance_estimate(map, p, n, settings_.estimate, scratch);
        const Rgb<float> back = irradiance_estimate(map, p, -n, settings_.estimate, scratch);
        x.side = back.luminance() > front.luminance() ? T(-1) : T(1);
        const Rgb<float> e = x.side > T(0) ? front : back;
        const Material<T>& m = s.materials[s.material_of[x.triangle]];
        out = m.specular() ? Rgb<T>(T(0)) : m.kd * Rgb<T>(T(e[0]), T(e[1]), T(e[2])) / pi<T>;
    }

    template <RayAccelerator A>
    void gather(const Scene<T>& s, const A& accel, const std::vector<std::uint32_t>& ids) {
        detail::parallel_blocks(int((ids.size() + 15) / 16), settings_.threads, [&](std::atomic<int>& next) {
            for (int b = next++; b < int((ids.size() + 15) / 16); b = next++)
                for (std::size_t k = std::size_t(b) * 16; k < std::min(ids.size(), std::size_t(b + 1) * 16); ++k) {
                    const Texel& x = texels_[ids[k]];
                    const Vec3<T> p = position(s, x), n = s.normal(x.triangle) * x.side;
                    iim_[ids[k]] = plane_.gather(accel, p, n, [&](const Ray<T>& r, const StoreHit<T>& h) {
                        return aim_[texel_at(s, h.id, r.at(h.t))];
                    });
                }
        });
    }

    TexelCacheSettings settings_;
    SurfaceGroups groups_;
    HemiPlane<T> plane_;
    std::vector<Texel> texels_;
    std::vector<Tiling> tiling_;
    std::vector<std::uint32_t> cell_;                  // per triangle, 2 n^2 cells -> texel
    std::vector<std::vector<std::uint32_t>> by_group_;  // texels of each group
    std::vector<Rgb<T>> aim_, iim_;
    std::vector<float> delta_f_, delta_i_, area_;       // per group
    std::vector<std::size_t> cursor_;                   // per group: next texel of its IIM pass
};

}  // namespace glint
