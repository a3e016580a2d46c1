// glint/lights/cuts.hpp: the cut of a light cluster tree (lights/cluster_tree.hpp) at one
// shading point, Fernandez 2004, §5.1.3-5.2 (dense cuts).
//
// A node C stands for its lights by the cluster approximation
//   L_C ~ f_C G_C V_rep I_C,   I_C = sum of the lights' intensities,
// with G = cos_x falloff(light) / d^2 (eq. 5.3; falloff = the oriented light's cosine), f_C G_C
// that of a light with the representative's profile at the node's power-weighted centroid
// along its mean axis, at most the node's bound f_max G_max per band, and V_rep the
// representative's visibility. Eq. 5.4 takes f G at the representative (f_rep G_rep V_rep I_C);
// the centroid's is right to first order in the lights' spread (lower image error for the
// same cuts: docs/lights.md). A leaf's centroid is its light: leaves are exact. The cut starts at the root; the node with the largest error estimate
//   Error(C) = 0.5 f_max G_max I_C                          (CutError::bound, the default)
//   Error(C) = max(0.5 f_max G_max I_C, f_C G_C V_rep I_C)  (CutError::fernandez, eq. 5.8-5.10)
// is replaced by its children until every node's error is at most `threshold` times the
// running total (the sum of the cut's approximations: 2% by default, Weber's law, eq. 5.5) or
// the cut has max_nodes nodes (300). A leaf is exact (error 0). A node's representative is one
// of its children's, so refining a node traces one new shadow ray (the other child reuses the
// parent's V): one shadow ray per node of the cut.
// The bounds, from the node's box (centre c relative to x, size s) in the frame (u, v, w):
//   d_min^2 = sum_k max(|c_k| - s_k / 2, 0)^2                                  (eq. 5.6)
//   cos_max(w) = w_max / sqrt(u_min^2 + v_min^2 + w_max^2), 0 when w_max <= 0,  (eq. 5.7)
//     u_min = max(|u.c| - (s . |u|) / 2, 0), likewise v_min, w_max = w.c + (s . |w|) / 2
//   f_max = kd / pi + ks (n + 2) / (2 pi) cos_max(mirror)^n (the Phong bound: eq. 5.7 about
//     the mirror direction), G_max = cos_max(normal) e_max / max(d_min^2, d_clamp^2),
//   e_max = the light-side bound: cos(max(0, theta - theta_o - theta_b)) for cosine lights,
//     1 for others, 0 beyond theta_e (the node's orientation cone; theta = angle from the
//     cone's axis to x, theta_b = the box's half angle seen from x).
// Repaired from the seed's text: eq. 5.7's w term is signed (w.c, not |w.c|: a box behind the
// surface bounds the cosine by 0) and its corners read p = (+-s_x, +-s_y, +-s_z) / 2; eq. 5.9's
// I_max is the node's total I_C (the bound is on the sum over its lights; V_max = 1); eq.
// 5.10's sum runs over the node's lights j, not the node index i. The light-side bound e_max
// is not in the seed (which bounds only the receiver's cosine); it is Walter et al. 2005's
// and Conty Estevez and Kulla 2018's orientation-cone bound. Each node's true error, with its
// representative's visibility, is at most f_max G_max I_C; one accepted by the threshold has
// at most twice the threshold times the running total (§5.1.4), under either estimate.
// The default refines on the bound alone, as Walter et al. 2005 do (their threshold is on
// f_max G_max I_C; the 0.5 keeps the seed's scale): the seed's second term refines nodes whose
// representative is bright, which their bound already ranks (fewer nodes at the same image
// error: docs/lights.md).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/lights/cluster_tree.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/brdf.hpp>

namespace glint {

/// The error estimate a cut refines on (lights/cuts.hpp's header): half the node's bound
/// (Walter et al. 2005's criterion), or Fernandez 2004's eq. 5.8-5.10, the larger of that and
/// the node's approximation.
enum class CutError : std::uint8_t { bound, fernandez };

/// The cut's knobs: relative error threshold, largest cut (0: unlimited) and error estimate.
struct CutSettings {
    double threshold = 0.02;  ///< Largest node error relative to the cut's running total (0.02: Weber's 2%); >= 0.
    int max_nodes = 300;      ///< Most nodes in a cut (0: unlimited); >= 0.
    CutError error = CutError::bound;  ///< The error estimate the cut refines on.

    /// Throws Error unless threshold is finite and >= 0 and max_nodes >= 0.
    void validate() const {
        if (!(threshold >= 0) || !std::isfinite(threshold))
            throw Error("glint::CutSettings: threshold " + std::to_string(threshold) + " must be finite and >= 0");
        if (max_nodes < 0) throw Error("glint::CutSettings: max_nodes " + std::to_string(max_nodes) + " must be >= 0");
    }
};

/// The shading point as a cut sees it: position, unit normal (the lit side), local frame, BRDF
/// and the squared distance the geometry term is clamped at (0: none).
template <Scalar T>
struct CutReceiver {
    /// Position of the shading point (world space).
    Vec3<T> x, n;  ///< Unit normal at x, on the lit side.
    Frame<T> frame;              ///< Local shading frame whose n axis is the normal.
    const SurfaceBrdf<T>* brdf;  ///< BRDF at x (not owned; non-null).
    T d2min = T(0);              ///< Squared distance the geometry term's 1/d^2 is clamped at (0: none).
    Frame<T> mirror;             ///< Frame about the Phong lobe's mirror direction (glossy BRDFs).

    /// The receiver at x_ with normal n_, frame f and BRDF b (non-null); the mirror frame is
    /// derived from b's mirror direction.
    CutReceiver(const Vec3<T>& x_, const Vec3<T>& n_, const Frame<T>& f, const SurfaceBrdf<T>* b, T d2min_)
        : x(x_), n(n_), frame(f), brdf(b), d2min(d2min_), mirror(Frame<T>::from_normal(f.to_world(b->mirror()))) {}
};

namespace detail {

/// Eq. 5.7: a bound on the cosine between unit w and the directions from the receiver to the
/// box whose centre is at c (relative) and half size h; (a, b, w) orthonormal.
template <Scalar T>
T box_cos_bound(const Vec3<T>& c, const Vec3<T>& h, const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& w) {
    const T w_max = glm::dot(w, c) + glm::dot(h, glm::abs(w));
    if (!(w_max > T(0))) return T(0);
    const T a_min = std::max(std::abs(glm::dot(a, c)) - glm::dot(h, glm::abs(a)), T(0));
    const T b_min = std::max(std::abs(glm::dot(b, c)) - glm::dot(h, glm::abs(b)), T(0));
    return std::min(T(1), w_max / std::sqrt(a_min * a_min + b_min * b_min + w_max * w_max));
}

/// The light-side bound e_max of a node seen from x (1 for a node with non-cosine lights):
/// cos(max(0, theta - theta_o - theta_b)) by the angle-difference identities (no inverse
/// trigonometry), raised by 1e-4 against rounding.
template <Scalar T>
T emission_bound(const LightNode<T>& node, const Vec3<T>& x) {
    if (node.theta_o >= pi<T>) return T(1);
    const Vec3<T> d = x - node.box.center();
    const T dist2 = glm::dot(d, d);
    const Vec3<T> e = node.box.extent();
    const T radius2 = glm::dot(e, e) * T(0.25);
    if (dist2 <= radius2) return T(1);
    const T inv = T(1) / std::sqrt(dist2);
    const T cos_t = glm::dot(node.axis, d) * inv;
    if (cos_t >= node.cos_o) return T(1);  // theta <= theta_o
    const T sin_t = std::sqrt(std::max(T(0), T(1) - cos_t * cos_t));
    const T cos_a = cos_t * node.cos_o + sin_t * node.sin_o;  // theta - theta_o, in (0, pi]
    const T sin_a = std::max(T(0), sin_t * node.cos_o - cos_t * node.sin_o);
    const T sin_b = std::sqrt(radius2) * inv, cos_b = std::sqrt(std::max(T(0), T(1) - sin_b * sin_b));
    if (cos_a >= cos_b) return T(1);  // theta - theta_o <= theta_b
    const T c = std::min(T(1), cos_a * cos_b + sin_a * sin_b + T(1e-4));
    if (c <= node.cos_e) return T(0);
    return node.cosine ? c : T(1);
}

}  // namespace detail

/// f_max G_max I_C of eq. 5.9 (per band) for node `node` at receiver r.
template <Scalar T>
Rgb<T> node_bound(const LightNode<T>& node, const CutReceiver<T>& r) {
    const Vec3<T> c = node.box.center() - r.x, h = node.box.extent() * T(0.5);
    const T cos_x = detail::box_cos_bound(c, h, r.frame.s, r.frame.t, r.frame.n);
    if (cos_x <= T(0)) return Rgb<T>(T(0));
    const T e = detail::emission_bound(node, r.x);
    if (e <= T(0)) return Rgb<T>(T(0));
    const Vec3<T> dmin = glm::max(glm::abs(c) - h, Vec3<T>(0));
    const T d2 = std::max(glm::dot(dmin, dmin), r.d2min);
    if (!(d2 > T(0))) return Rgb<T>(infinity<T>);
    Rgb<T> f = r.brdf->kd() / pi<T>;
    if (r.brdf->lobe_count() > 1) {
        const T cos_m = detail::box_cos_bound(c, h, r.mirror.s, r.mirror.t, r.mirror.n);
        const T n = r.brdf->exponent();
        if (cos_m > T(0)) f += r.brdf->ks() * ((n + T(2)) / (T(2) * pi<T>) * std::pow(cos_m, n));
    }
    return f * node.intensity * (cos_x * e / d2);
}

/// f G of light l at receiver r without visibility (per unit intensity); 0 where the light
/// cannot contribute (behind the surface or the light, or no reflection).
template <Scalar T>
Rgb<T> light_factor(const PointLight<T>& l, const CutReceiver<T>& r) {
    const Vec3<T> d = l.position - r.x;
    const T r2 = glm::dot(d, d);
    if (!(r2 > T(0))) return Rgb<T>(T(0));
    const Vec3<T> wi = d / std::sqrt(r2);
    const T cos_x = glm::dot(r.n, wi);
    if (cos_x <= T(0)) return Rgb<T>(T(0));
    const T e = l.falloff(-wi);
    if (e <= T(0)) return Rgb<T>(T(0));
    return r.brdf->f(r.frame.to_local(wi)) * (cos_x * e / std::max(r2, r.d2min));
}

/// f_C G_C of node n at receiver r (per unit intensity, without visibility): light_factor of
/// the node's representative `rep` moved to the node's centroid and turned to its mean axis.
template <Scalar T>
Rgb<T> node_factor(const LightNode<T>& n, const PointLight<T>& rep, const CutReceiver<T>& r) {
    PointLight<T> l = rep;
    l.position = n.centroid;
    l.axis = n.mean_axis;
    return light_factor(l, r);
}

/// What a cut did at one point.
template <Scalar T>
struct CutResult {
    Rgb<T> L{T(0)};       ///< The cut's radiance sum_C L_C reflected at the point.
    int nodes = 0;        ///< Nodes in the final cut.
    int shadow_rays = 0;  ///< Shadow rays traced (one per representative evaluated).
};

/// One accepted node, for tests: its approximation, bound (f_max G_max I_C), its f_C G_C V_rep
/// per unit intensity and its representative's visibility, and whether it met the threshold
/// (else the cut was full) with the threshold's value then.
template <Scalar T>
struct CutRecord {
    std::uint32_t node;  ///< The node's index in the tree.
    /// The node's approximation f_rep G_rep V_rep I_C (per band).
    Rgb<T> estimate, bound, factor;
    /// \var bound
    /// The node's error bound f_max G_max I_C, per band.
    /// \var factor
    /// The node's f_C G_C (at most its bound) per unit intensity, times V_rep.

    /// Whether the representative's shadow ray was unoccluded.
    bool visible, by_threshold;  ///< Whether the node met the threshold (false: accepted because the cut was full).
    T allowed;  ///< Threshold times the running total (luminance) when the node was accepted.
};

namespace detail {

// The cut's max-heap of (error, ...) entries on the caller's vector, 4-ary: half the levels
// of a binary heap for the hole a pop sends down (the cut's heap holds ~100-300 entries), the
// largest of up to four children chosen by selects (a cut's errors make a branch a coin toss).

/// Puts e into the hole at i, moving it up past every parent with a smaller error.
template <class Entry>
void heap_sift_up(std::vector<Entry>& h, std::size_t i, const Entry& e) {
    for (; i > 0; i = (i - 1) / 4) {
        const std::size_t parent = (i - 1) / 4;
        if (!(h[parent].error < e.error)) break;
        h[i] = h[parent];
    }
    h[i] = e;
}

/// Adds e to heap h.
template <class Entry>
void heap_push(std::vector<Entry>& h, const Entry& e) {
    h.push_back(e);
    heap_sift_up(h, h.size() - 1, e);
}

/// Removes and returns the largest entry of the non-empty heap h: the hole left at the top
/// descends along the largest children to a leaf, where the last entry goes and climbs.
template <class Entry>
Entry heap_pop(std::vector<Entry>& h) {
    const Entry top = h[0], last = h.back();
    h.pop_back();
    const std::size_t n = h.size();
    if (n == 0) return top;
    std::size_t i = 0;
    for (std::size_t c = 1; c < n; c = 4 * i + 1) {
        std::size_t m = c;  // ties: the last of the largest
        for (std::size_t k = c + 1; k < std::min(c + 4, n); ++k) m = !(h[k].error < h[m].error) ? k : m;
        h[i] = h[m];
        i = m;
    }
    heap_sift_up(h, i, last);
    return top;
}

/// The nodes a cut has evaluated: each node's error and its slot in `evals`, its evaluation
/// (f_C G_C V_rep, and V_rep, which a child with its parent's representative reuses).
template <Scalar T, class Visible, class Interpolate>
struct CutSearch {
    struct Entry {
        T error;
        std::uint32_t node, slot;
        bool operator<(const Entry& o) const { return error < o.error; }
    };
    struct Evaluation {
        Rgb<T> factor;  // f_C G_C V_rep per unit intensity
        bool visible;   // V_rep
        bool traced;    // whether V_rep was traced (not when f_C G_C = 0)
    };

    const LightClusterTree<T>& tree;
    const CutReceiver<T>& r;
    Visible& visible;
    Interpolate& interpolate;
    CutResult<T>& out;
    std::vector<Evaluation>& evals;
    bool fernandez;  ///< CutError::fernandez: the error is the larger of half the bound and the approximation.

    /// Node k's entry (into `made`; through a reference, not returned with the luminance as a
    /// pair: that measured a store-forwarding stall per node) and its approximation's
    /// luminance; `parent`: the entry it refines.
    T entry(std::uint32_t k, const Entry* parent, Entry& made) {
        const LightNode<T>& n = tree.node(k);
        const T relative = interpolate(k, parent ? parent->node : LightNode<T>::none);
        if (relative >= T(0)) {  // interpolated: the representative's f G times the relative value, no ray
            made = Entry{T(0), k, std::uint32_t(evals.size())};
            evals.push_back({light_factor(tree.lights()[n.rep], r) * relative, true, false});
            return (evals.back().factor * n.intensity).luminance();
        }
        const Rgb<T> bound = n.leaf() ? Rgb<T>(T(0)) : node_bound(n, r);
        const PointLight<T>& rep = tree.lights()[n.rep];
        Evaluation e{node_factor(n, rep, r), false, false};
        if (e.factor.max() > T(0)) {
            const Evaluation* shared = parent && tree.node(parent->node).rep == n.rep ? &evals[parent->slot] : nullptr;
            if (shared && shared->traced) {
                e.visible = shared->visible;
            } else {
                ++out.shadow_rays;
                e.visible = visible(rep);
            }
            e.traced = true;
        }
        if (!e.visible) e.factor = Rgb<T>(T(0));
        for (std::size_t c = 0; c < 3 && !n.leaf(); ++c)  // at most the bound (then I_C > 0 in the band)
            if (e.factor[c] * n.intensity[c] > bound[c]) e.factor[c] = bound[c] / n.intensity[c];
        const T est = (e.factor * n.intensity).luminance();
        const T half_bound = T(0.5) * bound.luminance();
        made = Entry{fernandez && !n.leaf() ? std::max(half_bound, est) : half_bound, k, std::uint32_t(evals.size())};
        evals.push_back(e);
        return est;
    }

    /// Adds node e to the cut (and to `trace`).
    void accept(const Entry& e, T allowed, bool by_threshold, std::vector<CutRecord<T>>* trace) {
        const LightNode<T>& n = tree.node(e.node);
        const Evaluation& ev = evals[e.slot];
        out.L += ev.factor * n.intensity;
        ++out.nodes;
        if (trace) trace->push_back({e.node, ev.factor * n.intensity, node_bound(n, r), ev.factor, ev.visible, by_threshold, allowed});
    }
};

}  // namespace detail

/// The cut of `tree` at r (`visible(light)`: its shadow ray), its radiance sum_C L_C.
/// `interpolate(node, parent)` (parent: LightNode::none at the root), asked of every node the
/// cut reaches before its shadow ray, returns a relative value R >= 0 to take the node as
/// R f_rep G_rep I_C without a ray (accepted as it comes), or a negative value for the dense
/// cut's treatment (lights/sparse_direct.hpp's reconstruction cuts). `trace`, when given,
/// receives every accepted node.
template <Scalar T, class Visible, class Interpolate>
CutResult<T> evaluate_cut(const LightClusterTree<T>& tree, const CutReceiver<T>& r, const CutSettings& s, Visible&& visible,
                          Interpolate&& interpolate, std::vector<CutRecord<T>>* trace = nullptr) {
    using Search = detail::CutSearch<T, std::remove_reference_t<Visible>, std::remove_reference_t<Interpolate>>;
    using Entry = typename Search::Entry;
    CutResult<T> out;
    if (tree.empty()) return out;
    thread_local std::vector<Entry> heap;
    thread_local std::vector<typename Search::Evaluation> evals;
    heap.clear();
    evals.clear();
    Search search{tree, r, visible, interpolate, out, evals, s.error == CutError::fernandez};
    T total = 0;  // the running total: the sum of the cut's approximations
    // A node of error 0 (a leaf, or one that cannot contribute) is accepted as it comes.
    // Node k (refining `parent`) into the cut's heap, or straight into the cut.
    const auto add = [&](std::uint32_t k, const Entry* parent) {
        Entry en;
        total += search.entry(k, parent, en);
        if (en.error > T(0)) {
            detail::heap_push(heap, en);
            return;
        }
        search.accept(en, T(s.threshold) * total, true, trace);
    };
    add(tree.root(), nullptr);
    const std::size_t cap = s.max_nodes > 0 ? std::size_t(s.max_nodes) : ~std::size_t(0);
    while (!heap.empty()) {
        const Entry e = detail::heap_pop(heap);
        const LightNode<T>& n = tree.node(e.node);
        const T allowed = T(s.threshold) * total;
        if (e.error <= allowed) {  // the largest error is within the threshold: so is every other
            search.accept(e, allowed, true, trace);
            for (const Entry& rest : heap) search.accept(rest, allowed, true, trace);
            break;
        }
        if (std::size_t(out.nodes) + heap.size() + 1 >= cap) {
            search.accept(e, allowed, false, trace);
            continue;
        }
        total -= (evals[e.slot].factor * n.intensity).luminance();
        add(n.left, &e);
        add(n.right, &e);
    }
    return out;
}

/// The dense cut: no node interpolated.
template <Scalar T, class Visible>
CutResult<T> evaluate_cut(const LightClusterTree<T>& tree, const CutReceiver<T>& r, const CutSettings& s, Visible&& visible,
                          std::vector<CutRecord<T>>* trace = nullptr) {
    return evaluate_cut(tree, r, s, visible, [](std::uint32_t, std::uint32_t) { return T(-1); }, trace);
}

}  // namespace glint
