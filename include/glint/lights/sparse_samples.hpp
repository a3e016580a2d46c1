// glint/lights/sparse_samples.hpp: the sample cuts of Fernandez 2004's sparse sampling
// (§5.3-5.4), computed once from the camera's primary hits.
//
// A sample is a diffuse or glossy surface point x_i found by a camera ray through a Halton(2,3)
// point of the image (as lights/lie.hpp's construction), with its dense cut (lights/cuts.hpp)
// evaluated for a white Lambertian receiver. It keeps
//   - its irradiance E(x_i) = sum over the cut's nodes of E_C (eq. 5.11, the cluster
//     approximation E_C = G_rep V_rep I_C), for interpolation (eq. 5.12-5.14);
//   - the relative cluster irradiance of every node on or above its cut (eq. 5.15),
//     R_C(x_i) = E_C(x_i) / (G_rep(x_i) I_C), I_C = sum of the node's lights' intensities,
//     where a node above the cut has E_C = the sum of its cut nodes' E_C; a node below the cut
//     takes its nearest ancestor's value (§5.4.4). R is a luminance ratio.
// Storage (§5.4.4, Fig. 5.15): two arrays per sample in depth-first order, the root at 0 and a
// right child always one after its left child: R as 2-byte fixed point (12 fraction bits, 0 to
// 16; the value 0xffff marks "unknown": a representative that cannot reach x_i, or R >= 16),
// and the 2-byte index of the left child (0: none). Two children that are both on the cut and
// store their parent's value are collapsed into it, repeatedly.
// Repaired from the seed's text: eq. 5.15 uses i both for the sample and for the node's lights;
// its sum runs over the lights l of C, I_C = sum_l I_l, and x_i is the sample.
//
// Sample priorities (§5.4.3): with SparseSettings::priority = p > 0, the first (1 - p) of the
// samples are uniform over the image (Halton points 1, 2, ...); the rest are drawn among
// candidate points (the Halton points after them) with probability proportional to a priority,
// the size of the reconstruction cut at the candidate times its distance to the nearest sample
// (lights/sparse_direct.hpp computes it and calls add()).
//
// The samples' cuts are traced on `threads` threads, each sample into its own slot, and then
// packed in the order of their Halton indices: the samples are the same for any thread count.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/parallel.hpp>
#include <glint/lights/cut_direct.hpp>
#include <glint/lights/cuts.hpp>
#include <glint/lights/lie.hpp>
#include <glint/lights/sample_neighbours.hpp>

namespace glint {

/// Interpolation (§5.3.1) or reconstruction cuts (§5.3.2).
enum class SparseMode : std::uint8_t { interpolate, reconstruct };

/// Sparse sampling's knobs: mode, sample count and placement, neighbourhood, agreement and cuts.
struct SparseSettings {
    SparseMode mode = SparseMode::reconstruct;  ///< Interpolation or reconstruction cuts.
    int samples = 5000;       ///< Camera rays of the construction (about 5000 sample cuts per image); >= 1.
    int neighbours = 8;       ///< k: the nearest samples a point uses (eq. 5.12-5.13, 5.20), in [2, 32].
    double agreement = 0.05;  ///< t_interp of eq. 5.20; finite, >= 0 (0: never interpolate a node).
    /// The k-th sample farther (eq. 5.22) than this fraction of the scene's diagonal: dense cut; > 0.
    double max_radius = 0.1;
    double aspect = 1.0;      ///< Width / height of the image whose view is sampled; > 0.
    double priority = 0.0;    ///< The fraction of `samples` placed by priority (§5.4.3), in [0, 1); 0: all uniform.
    int candidates = 4;       ///< Candidate points per prioritized sample, in [1, 64].
    int threads = 0;          ///< Construction threads (0: all); the samples do not depend on it.
    /// The sample cuts, the dense fallback, and reconstruction's evaluation threshold;
    /// max_nodes must be in [1, 16000] (2-byte indices).
    CutSettings cut{};

    /// Throws Error naming the first setting out of its range (the ranges above).
    void validate() const {
        auto bad = [](const std::string& what) { throw Error("glint::SparseSettings: " + what); };
        if (samples < 1) bad("samples " + std::to_string(samples) + " must be >= 1");
        if (neighbours < 2 || neighbours > 32) bad("neighbours " + std::to_string(neighbours) + " must be in [2, 32]");
        if (!(agreement >= 0) || !std::isfinite(agreement)) bad("agreement " + std::to_string(agreement) + " must be finite and >= 0");
        if (!(max_radius > 0)) bad("max_radius " + std::to_string(max_radius) + " must be > 0");
        if (!(aspect > 0 && aspect < 1e6)) bad("aspect " + std::to_string(aspect) + " must be > 0");
        if (!(priority >= 0 && priority < 1)) bad("priority " + std::to_string(priority) + " must be in [0, 1)");
        if (candidates < 1 || candidates > 64) bad("candidates " + std::to_string(candidates) + " must be in [1, 64]");
        cut.validate();
        if (cut.max_nodes == 0 || cut.max_nodes > 16000)
            bad("cut.max_nodes " + std::to_string(cut.max_nodes) + " must be in [1, 16000] (2-byte indices)");
    }
    /// The samples placed by priority; the others (the first Halton points) are uniform.
    int prioritized() const { return int(std::lround(priority * double(samples))); }
    /// The samples placed uniformly: samples - prioritized().
    int uniform() const { return samples - prioritized(); }
};

/// The sample cuts of sparse sampling: per sample its position, normal, irradiance and packed
/// relative irradiances, with a kd-tree for neighbour queries. Not copyable (the kd-tree refers
/// to the positions); read-only and thread-safe once built.
template <Scalar T>
class SparseSamples {
public:
    static constexpr std::uint16_t unknown = 0xffff;  ///< Stored R meaning unknown (unreachable representative, or R >= 16).
    static constexpr T scale = T(4096);               ///< Fixed-point scale of a stored R: 12 fraction bits.

    /// The uniform samples of `scene` seen by its camera (Halton points 1 to s.uniform()),
    /// through `accel`, with cuts of `tree`.
    template <RayAccelerator A>
    SparseSamples(const Scene<T>& scene, const A& accel, const LightClusterTree<T>& tree, const SparseSettings& s) {
        s.validate();
        AABB<T> box;
        for (const auto& t : scene.triangles)
            for (const auto& v : t) box.extend(v);
        radius_ = T(s.max_radius) * glm::length(box.extent());
        std::vector<std::uint64_t> first(std::size_t(s.uniform()));
        std::iota(first.begin(), first.end(), std::uint64_t(1));
        add(scene, accel, tree, s, first);
    }
    /// Adds the samples at the Halton points `indices` (the camera's view, as the constructor's).
    template <RayAccelerator A>
    void add(const Scene<T>& scene, const A& accel, const LightClusterTree<T>& tree, const SparseSettings& s,
             std::span<const std::uint64_t> indices) {
        const int n = int(indices.size()), block = 32, blocks = (n + block - 1) / block;
        std::vector<Sample> all(indices.size());
        const Halton<T> halton(2);
        detail::parallel_blocks(blocks, s.threads, [&](std::atomic<int>& next) {
            for (int b; (b = next++) < blocks;)
                for (int i = b * block; i < std::min(n, (b + 1) * block); ++i)
                    all[std::size_t(i)] = make_sample(scene, accel, tree, s, halton, indices[std::size_t(i)]);
        });
        for (Sample& a : all)
            if (a.valid) pack(a);
        neighbours_ = SampleNeighbours<T>(x_, n_);
    }
    SparseSamples(const SparseSamples&) = delete;  // the kd-tree refers to x_ and n_
    SparseSamples& operator=(const SparseSamples&) = delete;

    /// Number of samples (camera rays that found a diffuse or glossy surface).
    std::size_t size() const { return x_.size(); }
    /// The Halton index of sample i's camera ray (lie_sample_ray).
    std::uint64_t halton_index(std::size_t i) const { return index_[i]; }
    /// Sample i's surface point (world space).
    const Vec3<T>& position(std::size_t i) const { return x_[i]; }
    /// Sample i's unit normal, facing the camera.
    const Vec3<T>& normal(std::size_t i) const { return n_[i]; }
    /// The sample's irradiance (eq. 5.11 summed over its cut).
    const Rgb<T>& irradiance(std::size_t i) const { return E_[i]; }
    /// Its packed relative irradiances (decode() each, unless `unknown`), one per kept node.
    std::span<const std::uint16_t> values(std::size_t i) const { return {values_.data() + first_[i], first_[i + 1] - first_[i]}; }
    /// Its left-child indices into values(i), one per kept node (0: none).
    std::span<const std::uint16_t> left(std::size_t i) const { return {left_.data() + first_[i], first_[i + 1] - first_[i]}; }
    /// Adds work done to place the samples (shading the prioritized samples' candidates).
    void count(int shadow_rays, int nodes) {
        rays_ += std::uint64_t(shadow_rays);
        nodes_ += std::uint64_t(nodes);
    }
    /// The shadow rays the samples' cuts (and their placement) cast, and their nodes, in all.
    std::uint64_t shadow_rays() const { return rays_; }
    /// The nodes of those cuts, in all.
    std::uint64_t cut_nodes() const { return nodes_; }
    /// The kernel's largest radius (world units).
    T radius() const { return radius_; }
    /// The k nearest samples of x (normal n) within radius(), nearest first.
    void nearest(const Vec3<T>& x, const Vec3<T>& n, int k, std::vector<SampleNeighbour<T>>& out) const {
        neighbours_.nearest(x, n, k, radius_, out);
    }
    /// Bytes per sample as stored: position, normal, irradiance, offset, and 4 bytes per kept node.
    double bytes_per_sample() const {
        if (x_.empty()) return 0;
        const double fixed = double(sizeof(Vec3<T>) * 2 + sizeof(Rgb<T>) + sizeof(std::uint32_t));
        return fixed + 4.0 * double(values_.size()) / double(x_.size());
    }
    /// The relative irradiance R a stored value v stands for (meaningless for `unknown`).
    static T decode(std::uint16_t v) { return T(v) / scale; }

private:
    struct Sample {
        bool valid = false;
        std::uint64_t index = 0;
        Vec3<T> x{0}, n{0};
        Rgb<T> E{T(0)};
        std::vector<std::uint16_t> values, left;
        int rays = 0, nodes = 0;
    };

    template <class A>
    static Sample make_sample(const Scene<T>& scene, const A& accel, const LightClusterTree<T>& tree, const SparseSettings& s,
                              const Halton<T>& h, std::uint64_t index) {
        Sample out;
        if (tree.empty()) return out;  // no lights: no samples, every point the (empty) dense cut
        std::optional<SurfaceBrdf<T>> brdf;
        ShadingPoint<T> sp;
        if (!lie_camera_point(scene, accel, lie_sample_ray(scene.camera, h, index, T(s.aspect)), brdf, sp)) return out;
        const Material<T> white = Material<T>::lambertian(Rgb<T>(T(1)));
        const SurfaceBrdf<T> unit(white, Vec3<T>(0, 0, 1));  // f = 1 / pi: the cut's L is E / pi
        const CutReceiver<T> r{sp.x, sp.n, sp.frame, &unit, T(0)};
        RayQueries<A> q(accel);
        std::vector<CutRecord<T>> trace;
        const CutResult<T> cut =
            evaluate_cut(tree, r, s.cut, [&](const PointLight<T>& l) { return CutDirect<T>::visible(sp, l, q); }, &trace);
        std::unordered_map<std::uint32_t, Rgb<T>> on_cut;
        for (const auto& c : trace) on_cut.emplace(c.node, c.estimate * pi<T>);
        out = Sample{true, index, sp.x, sp.n, cut.L * pi<T>, {0}, {0}, cut.shadow_rays, cut.nodes};
        encode(tree, r, on_cut, tree.root(), 0, out);
        return out;
    }

    /// Node k (at slot `slot` of the arrays) and the nodes under it down to the cut; returns E_C.
    static Rgb<T> encode(const LightClusterTree<T>& tree, const CutReceiver<T>& r,
                         const std::unordered_map<std::uint32_t, Rgb<T>>& on_cut, std::uint32_t k, std::size_t slot, Sample& out) {
        const LightNode<T>& node = tree.node(k);
        Rgb<T> E;
        if (const auto it = on_cut.find(k); it != on_cut.end()) {
            E = it->second;
        } else {
            const std::size_t l = out.values.size();
            out.values.resize(l + 2);
            out.left.resize(l + 2, 0);
            out.left[slot] = std::uint16_t(l);
            E = encode(tree, r, on_cut, node.left, l, out) + encode(tree, r, on_cut, node.right, l + 1, out);
        }
        const T g = light_factor(tree.lights()[node.rep], r).luminance() * pi<T>, i = node.intensity.luminance();
        const T R = E.luminance() / (g * i);
        out.values[slot] = g > T(0) && i > T(0) && R < T(65534) / scale ? std::uint16_t(std::lround(R * scale)) : unknown;
        const std::size_t l = out.left[slot];
        if (l != 0 && l + 2 == out.values.size() && out.left[l] == 0 && out.left[l + 1] == 0 &&
            out.values[l] == out.values[slot] && out.values[l + 1] == out.values[slot]) {
            out.values.resize(l);  // both children say what the parent says: collapse them
            out.left.resize(l);
            out.left[slot] = 0;
        }
        return E;
    }

    void pack(const Sample& a) {
        index_.push_back(a.index);
        x_.push_back(a.x);
        n_.push_back(a.n);
        E_.push_back(a.E);
        values_.insert(values_.end(), a.values.begin(), a.values.end());
        left_.insert(left_.end(), a.left.begin(), a.left.end());
        first_.push_back(std::uint32_t(values_.size()));
        rays_ += std::uint64_t(a.rays);
        nodes_ += std::uint64_t(a.nodes);
    }

    std::vector<std::uint64_t> index_;
    std::vector<Vec3<T>> x_, n_;
    std::vector<Rgb<T>> E_;
    std::vector<std::uint16_t> values_, left_;
    std::vector<std::uint32_t> first_{0};
    std::uint64_t rays_ = 0, nodes_ = 0;
    T radius_ = 0;
    SampleNeighbours<T> neighbours_;
};

}  // namespace glint
