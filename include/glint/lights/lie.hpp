// glint/lights/lie.hpp: local illumination environments (Fernandez 2004, ch. 3-4): an octree
// over the scene whose leaf cells record, per light, absent (fully occluded), unoccluded, or
// partial with the blocker triangles found for it (lights/lie_states.hpp).
//
// Built once, at construction, from N image samples: Halton(2,3) points of the image plane
// (§4.5) whose camera rays find surface points; from each, one shadow ray per light (to its
// point; area lights are points on them, lie_lights()), whose first blocker feeds the state
// machine of the cell holding the point (§3.1.1, Fig. 3.2). The rays of a batch of samples are
// traced on `threads` threads; the samples are then applied in their Halton order on one
// thread, so the LIEs are the same for any thread count. Unlike the thesis's interactive
// system (lazy construction, refined while the user walks), nothing is written while
// rendering: rendering threads only read.
//
// Subdivision (LieSettings::subdivision): fixed (cells of one depth, 6 by default, §4.3) or
// adaptive (§4.4: the root is one cell; a cell in which a light's list grows past
// blocker_threshold is split, its LIE discarded and its children started empty, down to
// max_depth, 8 by default). Variant: blocker lists, or three states (§4.7: no lists; partial
// lights get an ordinary shadow ray through the accelerator).
//
// Bias: a cell's states are what its samples saw. A light is absent where no sample saw it, a
// blocker is missing where no sample found it; points of the cell the samples missed then get the wrong answer (§4.8: every
// shadow-ray region needs one sample; small regions need many). Where no sample reached a cell,
// shading falls back to plain shadow rays (LieDirect), which is exact.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/parallel.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/lights/lie_octree.hpp>
#include <glint/lights/lie_states.hpp>
#include <glint/lights/light.hpp>
#include <glint/sampling/halton.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/tracer/shading.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// How the octree is subdivided: cells of one depth (§4.3) or split where blocker lists grow (§4.4).
enum class LieSubdivision : std::uint8_t { fixed, adaptive };
/// What a cell keeps for a partial light: its blocker list, or only the state (§4.7).
enum class LieVariant : std::uint8_t { blocker_lists, three_state };

/// How the local illumination environments are built: sampling, subdivision, variant and masking.
struct LieSettings {
    int samples = 1 << 16;  ///< Image samples (camera rays) of the construction; >= 1.
    LieSubdivision subdivision = LieSubdivision::fixed;  ///< Fixed-depth (§4.3) or adaptive (§4.4) cells.
    int depth = 6;              ///< Fixed subdivision: the cells' depth, in [0, 20].
    int max_depth = 8;          ///< Adaptive: no split below this depth, in [0, 20].
    int blocker_threshold = 8;  ///< Adaptive: split a cell when a light's list grows past this; >= 1.
    LieVariant variant = LieVariant::blocker_lists;  ///< Blocker lists, or three states without lists (§4.7).
    bool early_blockers = true;   ///< Keep blockers met before a light is seen (lights/lie_states.hpp).
    double mask_fraction = 0.02;  ///< Masking's budget: this fraction of a cell's minimum total, in [0, 1).
    int area_samples = 16;        ///< Points per polygon area light; >= 1.
    double aspect = 1.0;          ///< Width / height of the image whose view is sampled; > 0.
    int threads = 0;              ///< Construction threads (0: all); the result does not depend on it.

    /// Throws Error naming the first setting out of its range.
    void validate() const {
        auto bad = [](const std::string& what) { throw Error("LieSettings: " + what); };
        if (samples < 1) bad("samples must be >= 1, got " + std::to_string(samples));
        if (depth < 0 || depth > 20) bad("depth must be in [0, 20], got " + std::to_string(depth));
        if (max_depth < 0 || max_depth > 20) bad("max_depth must be in [0, 20], got " + std::to_string(max_depth));
        if (blocker_threshold < 1) bad("blocker_threshold must be >= 1, got " + std::to_string(blocker_threshold));
        if (!(mask_fraction >= 0 && mask_fraction < 1)) bad("mask_fraction must be in [0, 1), got " + std::to_string(mask_fraction));
        if (area_samples < 1) bad("area_samples must be >= 1, got " + std::to_string(area_samples));
        if (!(aspect > 0 && aspect < 1e6)) bad("aspect must be > 0, got " + std::to_string(aspect));
    }
};

/// A light of the LIE: a point emitter and, for a point on an area light, its position's
/// rounding error and surface normal (the shadow ray's far end is offset off that surface).
template <Scalar T>
struct LieLight {
    PointLight<T> light;  ///< The emitter (a cosine-profile point for an area light's sample).
    Vec3<T> err{0};       ///< Rounding-error bound of the position, per axis (0 for a point light).
    Vec3<T> normal{0};    ///< Unit normal of the area light's surface (0 for a point light).
};

/// The scene's point lights, then `area_samples` points on each polygon area light (Halton(2,3)
/// points of its area, each an oriented emitter of intensity Le A / area_samples along the normal).
template <Scalar T>
std::vector<LieLight<T>> lie_lights(const Scene<T>& scene, int area_samples) {
    std::vector<LieLight<T>> out;
    for (const auto& l : scene.point_lights) out.push_back({l});
    const Halton<T> h(2);
    for (const auto& a : scene.area_lights) {
        const PolygonLight<T, 3> poly(std::span<const Vec3<T>>(a.vertices), a.emission);
        T m = 0;
        for (const auto& v : a.vertices) m = std::max({m, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
        for (int k = 0; k < area_samples; ++k) {
            const Vec3<T> y = poly.sampler().sample(Vec2<T>(h.sample(std::uint64_t(k + 1), 0), h.sample(std::uint64_t(k + 1), 1)));
            out.push_back({PointLight<T>::oriented(y, a.normal, a.emission * (a.area / T(area_samples))), coordinate_error(m), a.normal});
        }
    }
    return out;
}

/// The shadow ray from sp to light l, built as RayQueries::visible builds it (both ends offset
/// off their surfaces, stopping just short of the light), so that a test on it decides as the
/// path tracer's shadow ray does.
template <Scalar T>
Ray<T> lie_shadow_ray(const ShadingPoint<T>& sp, const LieLight<T>& l) {
    const Vec3<T>& y = l.light.position;
    const Vec3<T> xo = offset_origin(sp.x, sp.err, sp.ng, y - sp.x);
    const Vec3<T> yo = offset_origin(y, l.err, l.normal, xo - y);
    return Ray<T>{xo, yo - xo, T(0), T(1) - T(sizeof(T) == 4 ? 1e-4 : 1e-9)};
}

/// The construction's camera ray `index` (>= 1): through Halton(2,3) point `index` of the image.
template <Scalar T>
Ray<T> lie_sample_ray(const Camera<T>& camera, const Halton<T>& h, std::uint64_t index, T aspect) {
    return camera.ray(h.sample(index, 0), h.sample(index, 1), aspect);
}

/// The diffuse or glossy surface point that `ray` (a camera ray) finds through `accel`, as a
/// ShadingPoint whose BRDF is kept in `brdf`; false where it misses or meets a specular surface.
template <Scalar T, class A>
bool lie_camera_point(const Scene<T>& scene, const A& accel, const Ray<T>& ray, std::optional<SurfaceBrdf<T>>& brdf,
                      ShadingPoint<T>& sp) {
    StoreHit<T> hit;
    if (!accel.closest_hit(ray, hit)) return false;
    const Material<T> m = scene.material_at(hit.id, hit.u, hit.v);
    if (m.specular()) return false;
    sp = shading_point(scene, hit, scene.normal(hit.id), ray.direction);
    brdf.emplace(m, sp.frame.to_local(-ray.direction));
    sp.brdf = &*brdf;
    return true;
}

/// The local illumination environments of a scene (Fernandez 2004, ch. 3-4): an octree whose
/// reached leaf cells hold, per light, its state and blockers. Built once by the constructor
/// (cost: samples x lights shadow rays), then read-only and safe to share between threads.
template <Scalar T>
class Lie {
public:
    /// A blocker triangle, stored ready for the ray-triangle test.
    using BlockerRecord = Triangle<MollerTrumbore<T>>;
    /// One frozen cell: its entries are all_entries()[entry_begin, entry_begin + entry_count).
    struct Cell {
        /// First entry of the cell in all_entries().
        std::uint32_t entry_begin = 0, entry_count = 0, masked = 0, samples = 0;
        /// \var entry_count
        /// Number of the cell's entries (its present lights).
        /// \var masked
        /// Number of the cell's lights that masking drops (entries flagged LieEntry::masked).
        /// \var samples
        /// Construction samples that landed in the cell.

        T min_total = 0;  ///< Smallest total luminance of its samples (masking's reference).
    };

    /// Builds the LIEs of `scene` seen by its camera, tracing through `accel` (built over
    /// scene.triangles); throws glint::Error for bad settings before any work.
    template <RayAccelerator A>
        requires std::same_as<typename A::scalar_type, T>
    Lie(const Scene<T>& scene, const A& accel, const LieSettings& s) : settings_(s) {
        s.validate();
        scene.validate();
        lights_ = lie_lights(scene, s.area_samples);
        AABB<T> b;
        for (const auto& t : scene.triangles)
            for (const auto& v : t) b.extend(v);
        octree_ = LieOctree<T>(b);
        build(scene, accel);
    }

    /// The cell holding x, or LieOctree::none (outside the scene, or no sample reached it).
    std::uint32_t locate(const Vec3<T>& x) const { return octree_.locate(x); }
    /// Cell c (unchecked: c < cells().size()).
    const Cell& cell(std::uint32_t c) const { return cells_[c]; }
    /// The lights present in cell c (not absent), in light order.
    std::span<const LieEntry> entries(std::uint32_t c) const {
        return std::span<const LieEntry>(entries_).subspan(cells_[c].entry_begin, cells_[c].entry_count);
    }
    /// The blocker triangles of entry e, as records for the intersection test (empty unless e
    /// is partial under LieVariant::blocker_lists).
    std::span<const BlockerRecord> blockers(const LieEntry& e) const {
        return std::span<const BlockerRecord>(records_).subspan(e.blocker_begin, e.blocker_count);
    }
    /// The blocker triangles of entry e, as indices into the scene's triangles.
    std::span<const std::uint32_t> blocker_triangles(const LieEntry& e) const {
        return std::span<const std::uint32_t>(blocker_ids_).subspan(e.blocker_begin, e.blocker_count);
    }
    /// The lights, in the order LieEntry::light indexes (lie_lights()).
    const std::vector<LieLight<T>>& lights() const { return lights_; }
    /// Every reached cell, indexed by the octree leaves' cell numbers.
    const std::vector<Cell>& cells() const { return cells_; }
    /// The entries of every cell, cell after cell.
    const std::vector<LieEntry>& all_entries() const { return entries_; }
    /// The blocker lists of every entry, as scene triangle indices, entry after entry.
    const std::vector<std::uint32_t>& all_blocker_triangles() const { return blocker_ids_; }
    /// The octree over the scene whose leaves name the cells.
    const LieOctree<T>& octree() const { return octree_; }
    /// The settings the LIEs were built with.
    const LieSettings& settings() const { return settings_; }
    /// Bytes of the octree, the cells, their entries and blocker records.
    std::size_t bytes() const {
        return octree_.nodes().size() * sizeof(typename LieOctree<T>::Node) + cells_.size() * sizeof(Cell) +
               entries_.size() * sizeof(LieEntry) + blocker_ids_.size() * (sizeof(std::uint32_t) + sizeof(BlockerRecord));
    }

private:
    /// One image sample's surface point, and per light its outcome and contribution.
    struct Batch {
        std::vector<Vec3<T>> x;
        std::vector<std::uint8_t> valid;
        std::vector<std::int32_t> outcome;
        std::vector<T> contribution;
    };

    template <class A>
    void build(const Scene<T>& scene, const A& accel) {
        const std::size_t nl = lights_.size();
        const int batch = 4096, block = 64;
        Batch b{std::vector<Vec3<T>>(batch), std::vector<std::uint8_t>(batch), std::vector<std::int32_t>(batch * nl),
                std::vector<T>(batch * nl)};
        const Halton<T> halton(2);
        for (int first = 0; first < settings_.samples; first += batch) {
            const int n = std::min(batch, settings_.samples - first);
            detail::parallel_blocks((n + block - 1) / block, settings_.threads, [&](std::atomic<int>& next) {
                for (int k; (k = next++) < (n + block - 1) / block;)
                    for (int i = k * block; i < std::min(n, (k + 1) * block); ++i)
                        trace_sample(scene, accel, halton, std::uint64_t(first + i + 1), b, std::size_t(i));
            });
            for (int i = 0; i < n; ++i)
                if (b.valid[std::size_t(i)]) apply(b, std::size_t(i));
        }
        freeze(scene);
    }

    /// The camera ray through Halton point `index` of the image, and at its diffuse or glossy
    /// hit one shadow ray per light that can contribute (its first blocker found by closest_hit).
    template <class A>
    void trace_sample(const Scene<T>& scene, const A& accel, const Halton<T>& h, std::uint64_t index, Batch& b,
                      std::size_t i) const {
        const std::size_t nl = lights_.size();
        const Ray<T> ray = lie_sample_ray(scene.camera, h, index, T(settings_.aspect));
        std::optional<SurfaceBrdf<T>> brdf;
        ShadingPoint<T> sp;
        b.valid[i] = 0;
        if (!lie_camera_point(scene, accel, ray, brdf, sp)) return;
        b.valid[i] = 1;
        b.x[i] = sp.x;
        for (std::size_t j = 0; j < nl; ++j) {
            Rgb<T> c;
            std::int32_t& o = b.outcome[i * nl + j];
            b.contribution[i * nl + j] = T(0);
            if (!point_light_unshadowed(lights_[j].light, sp, c)) {
                o = lie_no_light;
                continue;
            }
            StoreHit<T> blocker;
            o = accel.closest_hit(lie_shadow_ray(sp, lights_[j]), blocker) ? std::int32_t(blocker.id) : lie_visible;
            if (o == lie_visible) b.contribution[i * nl + j] = c.luminance();
        }
    }

    /// Sample i into the cell holding it; an adaptive cell whose list grows past the threshold
    /// is split, its LIE discarded, and the sample goes on into the new child.
    void apply(const Batch& b, std::size_t i) {
        const std::size_t nl = lights_.size();
        const bool adaptive = settings_.subdivision == LieSubdivision::adaptive;
        for (;;) {
            const std::uint32_t n = adaptive ? octree_.descend(b.x[i], settings_.max_depth, false)
                                             : octree_.descend(b.x[i], settings_.depth, true);
            if (n == LieOctree<T>::none) return;
            auto& node = octree_.node(n);
            if (node.cell == LieOctree<T>::none) {
                node.cell = std::uint32_t(builders_.size());
                builders_.emplace_back(nl);
            }
            const std::size_t longest =
                builders_[node.cell].add_sample(std::span<const std::int32_t>(b.outcome).subspan(i * nl, nl),
                                                std::span<const T>(b.contribution).subspan(i * nl, nl),
                                                LieRules{settings_.variant == LieVariant::blocker_lists, settings_.early_blockers});
            if (!adaptive || longest <= std::size_t(settings_.blocker_threshold) || node.depth >= settings_.max_depth) return;
            builders_[octree_.split(n)] = LieCellBuilder<T>(0);  // discarded, as §4.4 does
        }
    }

    /// Every reached leaf's LIE in shading order, the blocker records, the leaves renumbered.
    void freeze(const Scene<T>& scene) {
        for (std::uint32_t n = 0; n < octree_.nodes().size(); ++n) {
            auto& node = octree_.node(n);
            if (node.first_child != LieOctree<T>::none || node.cell == LieOctree<T>::none) continue;
            const LieCellBuilder<T>& cb = builders_[node.cell];
            Cell c;
            const auto e = cb.freeze(T(settings_.mask_fraction), blocker_ids_, c.masked);
            c.entry_begin = std::uint32_t(entries_.size());
            c.entry_count = std::uint32_t(e.size());
            c.samples = cb.samples();
            c.min_total = cb.min_total();
            entries_.insert(entries_.end(), e.begin(), e.end());
            node.cell = std::uint32_t(cells_.size());
            cells_.push_back(c);
        }
        builders_.clear();
        builders_.shrink_to_fit();
        records_.reserve(blocker_ids_.size());
        for (std::uint32_t k : blocker_ids_) {
            const auto& t = scene.triangles[k];
            records_.emplace_back(t[0], t[1], t[2]);
        }
    }

    LieSettings settings_;
    std::vector<LieLight<T>> lights_;
    LieOctree<T> octree_;
    std::vector<LieCellBuilder<T>> builders_;
    std::vector<Cell> cells_;
    std::vector<LieEntry> entries_;
    std::vector<std::uint32_t> blocker_ids_;
    std::vector<BlockerRecord> records_;
};

}  // namespace glint
