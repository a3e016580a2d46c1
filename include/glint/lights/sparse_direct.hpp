// glint/lights/sparse_direct.hpp: SparseDirect, Fernandez 2004's sparse sampling (§5.3-5.4) as
// the path tracer's direct-lighting policy. One type; the mode (SparseSettings::mode) is a
// run-time value.
//
// The samples (lights/sparse_samples.hpp) are made once, at construction, from the camera's
// primary hits; rendering threads only read them. At a primary vertex (the one whose
// vertex_record the host passes) with k samples within the kernel's largest radius:
//   interpolate (§5.3.1): L = (k_d / pi) E(x), E(x) = sum_i p_i E(x_i) / sum_i p_i over the k
//     nearest samples (eq. 5.12, 5.14) with the Epanechnikov weights
//     p_i = (d_k^2 - d_i^2) / d_k^2 (eq. 5.13; d: eq. 5.22, d_k: the k-th nearest, weight 0);
//     where every weight is 0 (k samples at one distance) the nearest sample's E. No shadow
//     ray.
//   reconstruct (§5.3.2): the dense cut's search (lights/cuts.hpp) in which every node it
//     reaches is first offered for interpolation: if the k samples' relative irradiances R_j
//     (eq. 5.15, a node below a sample's cut taking its ancestor's) agree,
//       max_j |R_j - avg_j R_j| < t_interp avg_j R_j                    (eq. 5.20),
//     the node is R_0 f_rep G_rep I_C with R_0 the nearest sample's (eq. 5.21), no shadow
//     ray; otherwise it is evaluated as the dense cut evaluates it (the representative's
//     shadow ray, accepted below the threshold, else refined; leaves are exact).
// Elsewhere (secondary vertices, too few samples near, glossy vertices) the dense cut. Both
// modes are for Lambertian receivers, as the seed's (ED?L paths only): a glossy f varies
// across a node's lights, which neither the irradiance nor the relative irradiance of the
// samples sees (a root interpolated with f_rep at a glossy floor was off by up to 5x in the
// tests), so glossy vertices take the dense cut, whose bound refines where f varies. With t_interp = 0 no
// node agrees and the reconstruction cut is the dense cut exactly.
// Repaired or changed from the seed's text: eq. 5.13's distances are squared ratios of d, the
// k-th sample only sets the radius; eq. 5.20 compares max_j R_j with the average one-sidedly,
// here the largest deviation either way (a sample far below the rest disagrees too); all-zero
// R (every sample's representative occluded) agrees for t_interp > 0. The evaluation test of
// eq. 5.18 (I_C G_rep < 2% of the total, no bound, no visibility) is replaced by the dense
// cut's (its CutSettings::error estimate), so that the reconstruction never accepts a node
// the dense cut would refine: it costs a shadow ray per refined node whose representative is
// new.
//
// Bias: interpolation blurs every feature narrower than the samples' spacing (shadow edges
// above all, §5.3.2): its error is largest near them (tests/test_lights.cpp measures it).
// Reconstruction cuts interpolate only nodes whose samples agree within t_interp, so their
// extra error is where all k samples agree and the point does not (a shadow the samples miss).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <utility>
#include <span>
#include <vector>

#include <glint/core/random.hpp>
#include <glint/lights/cut_direct.hpp>
#include <glint/lights/lie_direct.hpp>
#include <glint/lights/sparse_samples.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/lighting.hpp>

namespace glint {

/// Sparse sampling (Fernandez 2004, §5.3-5.4) as a DirectLighting policy: deterministic,
/// interpolating or reconstructing at primary vertices from samples made at construction, the
/// dense cut elsewhere; copies share the samples and may run on any number of threads.
template <Scalar T = float>
class SparseDirect : public NoPixelStatistics<T> {
public:
    using vertex_record = typename NoPixelStatistics<T>::vertex_record;  ///< Empty: no per-pixel statistics.
    using BuildAccel = typename LieDirect<T>::BuildAccel;  ///< The same accelerator the LIE's construction builds.

    /// What shading one point did: its light, the cut's nodes (interpolation: 0), shadow rays,
    /// nodes interpolated, and whether it fell back to the dense cut.
    struct Shaded {
        Rgb<T> L{T(0)};  ///< Reflected direct radiance at the point.
        /// Nodes of the cut (0 when interpolated).
        int nodes = 0, shadow_rays = 0, interpolated = 0;
        /// \var shadow_rays
        /// Shadow rays traced.
        /// \var interpolated
        /// Nodes of a reconstruction cut taken by interpolation, without a ray.

        bool dense = false;  ///< The point fell back to the dense cut (a glossy vertex, or fewer than k samples near).
    };

    /// Samples through `accel` (over scene.triangles); lights as LightPointOptions says.
    /// With s.priority > 0, the uniform samples first, then those chosen by priority
    /// (prioritized()).
    template <RayAccelerator A>
    SparseDirect(const Scene<T>& scene, const A& accel, const LightPointOptions<T>& lights, const SparseSettings& s)
        : dense_((s.validate(), scene), lights, s.cut), settings_(s) {
        auto samples = std::make_shared<SparseSamples<T>>(scene, accel, dense_.tree(), s);
        samples_ = samples;
        if (s.prioritized() > 0) samples->add(scene, accel, dense_.tree(), s, prioritized(scene, accel, *samples));
    }
    /// Samples through an accelerator of its own (what a factory that has none calls).
    SparseDirect(const Scene<T>& scene, const LightPointOptions<T>& lights, const SparseSettings& s)
        : SparseDirect(scene, BuildAccel(std::span<const TriangleVertices<T>>(scene.triangles)), lights, s) {}

    /// The direct light at sp: shade()'s L at a primary vertex (rec non-null), the dense cut's
    /// estimate at a secondary one.
    template <class Q, class S>
        requires PointShadowQueries<Q, T> && Sampler<S, T>
    Rgb<T> estimate(const ShadingPoint<T>& sp, S& sampler, Q& queries, vertex_record* rec) const {
        if (!rec) return dense_.estimate(sp, sampler, queries, rec);  // a secondary vertex
        return shade(sp, queries).L;
    }

    /// The dense cut's weight of area-light emission met by a ray (0 for the area lights it covers).
    T emission_weight(const Arrival<T>& from, const Ray<T>& ray, const StoreHit<T>& hit) const {
        return dense_.emission_weight(from, ray, hit);
    }

    /// The direct light at primary vertex sp, and what it cost.
    template <class Q>
        requires PointShadowQueries<Q, T>
    Shaded shade(const ShadingPoint<T>& sp, Q& queries) const {
        return shade(sp, queries, settings_.mode);
    }
    /// The same in mode `mode`.
    template <class Q>
        requires PointShadowQueries<Q, T>
    Shaded shade(const ShadingPoint<T>& sp, Q& queries, SparseMode mode) const {
        thread_local std::vector<SampleNeighbour<T>> near;
        samples_->nearest(sp.x, sp.n, settings_.neighbours, near);
        const bool enough = near.size() == std::size_t(settings_.neighbours) && sp.brdf->lobe_count() == 1;
        if (enough && mode == SparseMode::interpolate)
            return Shaded{sp.brdf->kd() / pi<T> * interpolate(near), 0, 0, 0, false};
        const CutReceiver<T> r{sp.x, sp.n, sp.frame, sp.brdf, T(0)};
        const auto visible = [&](const PointLight<T>& l) { return CutDirect<T>::visible(sp, l, queries); };
        Shaded out;
        CutResult<T> c;
        if (enough && mode == SparseMode::reconstruct) {
            Agreement a{*samples_, dense_.tree(), near, T(settings_.agreement), 0};
            c = evaluate_cut(dense_.tree(), r, settings_.cut, visible, a);
            out.interpolated = a.interpolated;
        } else {
            c = evaluate_cut(dense_.tree(), r, settings_.cut, visible);
            out.dense = true;
        }
        out.L = c.L;
        out.nodes = c.nodes;
        out.shadow_rays = c.shadow_rays;
        return out;
    }

    /// Eq. 5.12-5.13 over the neighbours `near` (nearest first, the last one sets the radius).
    Rgb<T> interpolate(std::span<const SampleNeighbour<T>> near) const {
        const T dk2 = near.back().distance * near.back().distance;
        Rgb<T> sum(T(0));
        T weights = 0;
        for (std::size_t i = 0; i + 1 < near.size(); ++i) {
            const T p = dk2 > T(0) ? (dk2 - near[i].distance * near[i].distance) / dk2 : T(0);
            sum += samples_->irradiance(near[i].sample) * p;
            weights += p;
        }
        return weights > T(0) ? sum / weights : samples_->irradiance(near.front().sample);
    }

    /// The sparse samples made at construction.
    const SparseSamples<T>& samples() const { return *samples_; }
    /// The settings in force (mode and agreement as with() last set them).
    const SparseSettings& settings() const { return settings_; }
    /// The dense-cut policy used where the samples are not.
    const CutDirect<T>& dense() const { return dense_; }
    /// The light cluster tree shared with the dense cut.
    const LightClusterTree<T>& tree() const { return dense_.tree(); }
    /// The same samples and tree (shared, not rebuilt) in another mode or agreement.
    SparseDirect with(SparseMode mode, double agreement) const {
        SparseDirect d = *this;
        d.settings_.mode = mode;
        d.settings_.agreement = agreement;
        d.settings_.validate();
        return d;
    }

private:
    /// The Halton indices of the prioritized samples: s.prioritized() of the s.candidates times
    /// as many points after the uniform ones, drawn without replacement with probability
    /// proportional to §5.4.3's priority w, the size of the point's reconstruction cut (at
    /// least 1) times its distance (eq. 5.22) to the nearest sample (the kernel's radius where
    /// none is within it): the largest keys log(u) / w (Efraimidis and Spirakis 2006). Each
    /// candidate's key depends on its index only: the same for any thread count. The
    /// candidates' shadow rays and nodes count in the samples' cost.
    template <RayAccelerator A>
    std::vector<std::uint64_t> prioritized(const Scene<T>& scene, const A& accel, SparseSamples<T>& samples) const {
        const SparseSettings& s = settings_;
        const int m = s.prioritized() * s.candidates, blocks = (m + 31) / 32;
        std::vector<Candidate> c(static_cast<std::size_t>(m));
        const Halton<T> halton(2);
        detail::parallel_blocks(blocks, s.threads, [&](std::atomic<int>& next) {
            RayQueries<A> q(accel);
            for (int b; (b = next++) < blocks;)
                for (int i = b * 32; i < std::min(m, (b + 1) * 32); ++i)
                    c[std::size_t(i)] = candidate(scene, accel, q, halton, std::uint64_t(s.uniform() + 1 + i));
        });
        for (const Candidate& k : c) samples.count(k.shadow_rays, k.nodes);
        const auto n = std::min(std::size_t(s.prioritized()), c.size());
        std::partial_sort(c.begin(), c.begin() + std::ptrdiff_t(n), c.end(),
                          [](const Candidate& a, const Candidate& b) { return a.key > b.key; });
        std::vector<std::uint64_t> out;
        for (std::size_t i = 0; i < n && c[i].key > -infinity<double>; ++i) out.push_back(c[i].index);
        std::sort(out.begin(), out.end());
        return out;
    }

    /// A candidate point of prioritized(): its Halton index, its key log(u) / priority (-inf
    /// where the camera ray finds no diffuse point), and what shading it cost.
    struct Candidate {
        double key = -infinity<double>;
        std::uint64_t index = 0;
        int shadow_rays = 0, nodes = 0;
    };
    template <RayAccelerator A>
    Candidate candidate(const Scene<T>& scene, const A& accel, RayQueries<A>& q, const Halton<T>& h, std::uint64_t index) const {
        Candidate c;
        c.index = index;
        std::optional<SurfaceBrdf<T>> brdf;
        ShadingPoint<T> sp;
        if (!lie_camera_point(scene, accel, lie_sample_ray(scene.camera, h, index, T(settings_.aspect)), brdf, sp)) return c;
        std::vector<SampleNeighbour<T>> near;
        samples_->nearest(sp.x, sp.n, 1, near);
        const T distance = near.empty() ? samples_->radius() : near.front().distance;
        const Shaded r = shade(sp, q, SparseMode::reconstruct);
        c.shadow_rays = r.shadow_rays, c.nodes = r.nodes;
        const double w = double(std::max(1, r.nodes)) * double(distance);  // §5.4.3's priority
        Pcg32 rng = Pcg32::hashed(0x5a3b1e5ULL, index);
        if (w > 0) c.key = std::log(1.0 - rng.uniform<double>()) / w;  // log of a u in (0, 1]
        return c;
    }

    /// The reconstruction's interpolation test for the cut search: each neighbour's slot in its
    /// packed arrays per node reached (a node is reached only after its parent).
    struct Agreement {
        const SparseSamples<T>& samples;
        const LightClusterTree<T>& tree;
        std::span<const SampleNeighbour<T>> near;
        T tolerance;
        int interpolated;

        T operator()(std::uint32_t k, std::uint32_t parent) {
            thread_local std::vector<std::uint16_t> slots;
            const std::size_t K = near.size();
            if (slots.size() < tree.nodes().size() * K) slots.resize(tree.nodes().size() * K);
            T R[32], avg = 0;
            bool known = true;
            for (std::size_t j = 0; j < K; ++j) {
                const auto left = samples.left(near[j].sample);
                std::uint16_t slot = 0;
                if (parent != LightNode<T>::none) {
                    const std::uint16_t p = slots[parent * K + j];
                    slot = left[p] == 0 ? p : std::uint16_t(left[p] + (tree.node(parent).right == k ? 1 : 0));
                }
                slots[k * K + j] = slot;
                const std::uint16_t v = samples.values(near[j].sample)[slot];
                known = known && v != SparseSamples<T>::unknown;
                R[j] = SparseSamples<T>::decode(v);
                avg += R[j];
            }
            if (!known || !(tolerance > T(0))) return T(-1);
            avg /= T(K);
            T dev = 0;
            for (std::size_t j = 0; j < K; ++j) dev = std::max(dev, std::abs(R[j] - avg));
            if (!(dev < tolerance * avg || (avg == T(0) && dev == T(0)))) return T(-1);
            ++interpolated;
            return R[0];
        }
    };

    CutDirect<T> dense_;
    SparseSettings settings_;
    std::shared_ptr<const SparseSamples<T>> samples_;
};

}  // namespace glint
