// glint/trees/kdtree_builder.hpp: SAH kd-tree builder, O(n log n), after Wald and Havran,
// "On building fast kd-trees for ray tracing, and on doing that in O(N log N)" (2006).
//
// Szécsi 2009, §4.2 names the kd-tree (with BVH and BIH) as the scheme with
// the lowest expected number of intersections: its cell boundaries are placed around the
// objects. This builder places them by the surface area heuristic:
//
//   cost(split) = lambda * (K_T + K_I * (SA(V_L)/SA(V) * N_L + SA(V_R)/SA(V) * N_R))
//   cost(leaf)  = K_I * N
//
// - K_T (`traversal_cost`, default 1): one traversal step;
// - K_I (`intersection_cost`, default 0.07): one triangle test in units of K_T. Leaves are
//   padded to whole batches and tested with the SIMD batch kernel (8 triangles at once),
//   while a traversal step is a chain of dependent loads, compares and a hard-to-predict
//   choice, so a test costs far less than a step (docs/history/trees.md: the measurements);
// - lambda = 1 - `empty_bonus` (default 0.9) when one side is empty and has volume: the
//   empty-space cut-off of Wald and Havran, which favours cutting empty space away. Since
//   traversal never enters empty leaves, an empty cell costs no step of its own;
// - a node becomes a leaf when no split is cheaper than cost(leaf), or at depth
//   `max_depth` (default 8 + 1.3 log2 N, at most 56, which bounds the traversal stack).
//
// Candidate planes are the bounds of the triangles *clipped to the node's cell* (perfect
// splits): a triangle crossing the chosen plane is clipped to each child cell (Sutherland-
// Hodgman in double precision), and its events in the children come from the clipped
// polygon's bounds, rounded outward to T. Events of all three axes are sorted once at the
// root; at each node they are split into the children's lists by one linear pass that keeps
// the order, and only the (O(sqrt N)) clipped triangles' new events are sorted and merged in:
// O(N log N) overall. Planar triangles (flat along the axis) are put on the cheaper side.
// Triangles that can never be hit (a non-finite vertex, or exactly zero area) are left out
// (detail::can_be_hit in tree.hpp).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// SAH constants and depth limit of the kd-tree build (see above); checked by build().
struct KdBuildOptions {
    double traversal_cost = 1.0;      ///< K_T, one traversal step; positive and finite.
    double intersection_cost = 0.07;  ///< K_I, one triangle test in units of K_T; positive and finite.
    double empty_bonus = 0.1;         ///< lambda = 1 - empty_bonus for a split with an empty side; in [0, 1).
    int max_depth = 0;                ///< 0: 8 + 1.3 log2 N; always capped at 56; negative throws.
};

namespace detail {

/// Rounds a double bound outward to T, with a margin for the double rounding of clipping.
template <class T>
T round_down(double x) {
    x -= std::abs(x) * 0x1p-48;
    T f = static_cast<T>(x);
    if (static_cast<double>(f) > x) f = std::nextafter(f, -infinity<T>);
    return f;
}
template <class T>
T round_up(double x) {
    x += std::abs(x) * 0x1p-48;
    T f = static_cast<T>(x);
    if (static_cast<double>(f) < x) f = std::nextafter(f, infinity<T>);
    return f;
}

/// Bounds of triangle (a, b, c) clipped to `box` (Sutherland-Hodgman against the six
/// planes, in double). False when nothing of the triangle is inside the box.
inline bool clipped_bounds(const Vec3d& a, const Vec3d& b, const Vec3d& c, const AABB<double>& box,
                           AABB<double>& out) {
    std::array<Vec3d, 9> poly{a, b, c}, next{};
    std::size_t n = 3;
    for (int axis = 0; axis < 3 && n > 0; ++axis) {
        for (int side = 0; side < 2 && n > 0; ++side) {
            const double plane = side ? box.hi[axis] : box.lo[axis];
            auto dist = [&](const Vec3d& p) { return side ? plane - p[axis] : p[axis] - plane; };
            std::size_t m = 0;
            for (std::size_t i = 0; i < n; ++i) {
                const Vec3d& p = poly[i];
                const Vec3d& q = poly[(i + 1) % n];
                const double dp = dist(p), dq = dist(q);
                if (dp >= 0) next[m++] = p;
                if ((dp >= 0) != (dq >= 0) && m < 9) {
                    Vec3d x = p + (q - p) * (dp / (dp - dq));
                    x[axis] = plane;
                    next[m++] = x;
                }
            }
            n = std::min<std::size_t>(m, 9);
            poly = next;
        }
    }
    if (n == 0) return false;
    out = AABB<double>{};
    for (std::size_t i = 0; i < n; ++i) out.extend(poly[i]);
    out.lo = glm::max(out.lo, box.lo);
    out.hi = glm::min(out.hi, box.hi);
    return !out.empty();
}

template <class T>
struct KdEvent {
    enum Type : std::uint32_t { end = 0, planar = 1, start = 2 };
    T pos;
    std::uint32_t tri;
    std::uint32_t type;
    bool operator<(const KdEvent& o) const { return pos < o.pos || (pos == o.pos && type < o.type); }
};

template <class T>
class KdBuild {
public:
    using Event = KdEvent<T>;
    using Events = std::array<std::vector<Event>, 3>;

    KdBuild(std::span<const TriangleVertices<T>> tris, const KdBuildOptions& opt) : tris_(tris), opt_(opt) {
        // Costs outside these ranges make the SAH prefer leaves or splits without bound.
        const auto bad = [](const char* what, double v) {
            throw Error(std::string("glint::KdTreeBuilder: ") + what + ", got " + std::to_string(v));
        };
        if (!(opt.traversal_cost > 0) || !std::isfinite(opt.traversal_cost))
            bad("traversal_cost (K_T) must be positive and finite", opt.traversal_cost);
        if (!(opt.intersection_cost > 0) || !std::isfinite(opt.intersection_cost))
            bad("intersection_cost (K_I) must be positive and finite", opt.intersection_cost);
        if (!(opt.empty_bonus >= 0 && opt.empty_bonus < 1)) bad("empty_bonus must lie in [0, 1)", opt.empty_bonus);
        if (opt.max_depth < 0) bad("max_depth must be >= 0 (0: automatic)", double(opt.max_depth));
    }

    BuiltTree<T> run() {
        out_.kind = TreeKind::kd;
        out_.triangle_count = tris_.size();
        side_.assign(tris_.size(), 0);
        Events ev;
        std::size_t n = 0;
        for (std::uint32_t i = 0; i < tris_.size(); ++i) {
            const auto& t = tris_[i];
            if (!detail::can_be_hit(t)) continue;
            AABB<T> b;
            for (const auto& p : t) b.extend(p);
            out_.bounds.extend(b);
            add_events(ev, i, b);
            ++n;
        }
        for (auto& e : ev) std::sort(e.begin(), e.end());
        int depth = opt_.max_depth;
        if (depth <= 0) depth = static_cast<int>(8 + 1.3 * std::log2(double(std::max<std::size_t>(n, 1))));
        max_depth_ = std::min(depth, 56);
        out_.nodes.reserve(2 * n + 1);
        if (n == 0) {
            out_.nodes.push_back(BuildNode<T>{});
            return std::move(out_);
        }
        build(out_.bounds, std::move(ev), n, 0);
        return std::move(out_);
    }

private:
    static void add_events(Events& ev, std::uint32_t tri, const AABB<T>& b) {
        for (int k = 0; k < 3; ++k) {
            if (b.lo[k] == b.hi[k]) {
                ev[k].push_back({b.lo[k], tri, Event::planar});
            } else {
                ev[k].push_back({b.lo[k], tri, Event::start});
                ev[k].push_back({b.hi[k], tri, Event::end});
            }
        }
    }

    double sah(const AABB<T>& box, int k, T p, std::size_t nl, std::size_t nr, double inv_sa) const {
        AABB<T> l = box, r = box;
        l.hi[k] = p;
        r.lo[k] = p;
        const double pl = double(l.surface_area()) * inv_sa, pr = double(r.surface_area()) * inv_sa;
        double c = opt_.traversal_cost + opt_.intersection_cost * (pl * double(nl) + pr * double(nr));
        if (nl == 0 || nr == 0) c *= 1.0 - opt_.empty_bonus;
        return c;
    }

    struct Split {
        double cost;
        int axis = -1;  // -1: no split beats a leaf
        T plane = 0;
        bool planar_left = false;
    };

    /// Sweep (Wald-Havran section 4.2): per axis, for every plane p the triangles ending at
    /// p (p-), lying in p (p|) and starting at p (p+); the cheapest split, or axis -1.
    Split find_split(const AABB<T>& box, const Events& ev, std::size_t n, int depth) const {
        Split best{opt_.intersection_cost * double(n)};
        const double sa = double(box.surface_area());
        if (depth >= max_depth_ || !(sa > 0)) return best;
        const double inv_sa = 1.0 / sa;
        for (int k = 0; k < 3; ++k) {
            const auto& e = ev[k];
            std::size_t nl = 0, nr = n;
            for (std::size_t i = 0; i < e.size();) {
                const T p = e[i].pos;
                std::size_t pe = 0, pp = 0, ps = 0;
                while (i < e.size() && e[i].pos == p && e[i].type == Event::end) ++pe, ++i;
                while (i < e.size() && e[i].pos == p && e[i].type == Event::planar) ++pp, ++i;
                while (i < e.size() && e[i].pos == p && e[i].type == Event::start) ++ps, ++i;
                nr -= pp + pe;
                if (p > box.lo[k] && p < box.hi[k]) {
                    const double cl = sah(box, k, p, nl + pp, nr, inv_sa);
                    const double cr = sah(box, k, p, nl, nr + pp, inv_sa);
                    if (cl < best.cost) best = {cl, k, p, true};
                    if (cr < best.cost) best = {cr, k, p, false};
                }
                nl += ps + pp;
            }
        }
        return best;
    }

    /// Classify (Wald-Havran section 5.1) into side_: 1 left only, 2 right only, 3 both.
    void classify(const std::vector<Event>& e_k, const Split& s) {
        for (const Event& e : e_k) side_[e.tri] = 3;
        for (const Event& e : e_k) {
            if (e.type == Event::end && e.pos <= s.plane) side_[e.tri] = 1;
            else if (e.type == Event::start && e.pos >= s.plane) side_[e.tri] = 2;
            else if (e.type == Event::planar)
                side_[e.tri] = (e.pos < s.plane || (e.pos == s.plane && s.planar_left)) ? 1 : 2;
        }
    }

    /// The children's sorted events: the one-sided triangles' events as they are, the
    /// straddling triangles clipped to each child (new events merged in). Counts in nl, nr.
    void split_events(const Events& ev, int k, const AABB<T>& lbox, const AABB<T>& rbox, Events& lev, Events& rev,
                      std::size_t& nl, std::size_t& nr) const {
        Events lnew, rnew;
        nl = nr = 0;
        const AABB<double> lb{Vec3d(lbox.lo), Vec3d(lbox.hi)}, rb{Vec3d(rbox.lo), Vec3d(rbox.hi)};
        for (const Event& e : ev[k]) {
            if (e.type == Event::end) continue;  // one visit per triangle
            const std::uint8_t s = side_[e.tri];
            if (s == 1) ++nl;
            else if (s == 2) ++nr;
            else {
                const auto& t = tris_[e.tri];
                const Vec3d a(t[0]), b(t[1]), c(t[2]);
                AABB<double> cb;
                if (clipped_bounds(a, b, c, lb, cb)) add_events(lnew, e.tri, to_t(cb, lbox)), ++nl;
                if (clipped_bounds(a, b, c, rb, cb)) add_events(rnew, e.tri, to_t(cb, rbox)), ++nr;
            }
        }
        for (int a = 0; a < 3; ++a) {
            lev[a].reserve(ev[a].size() / 2 + lnew[a].size());
            rev[a].reserve(ev[a].size() / 2 + rnew[a].size());
            for (const Event& e : ev[a]) {
                const std::uint8_t s = side_[e.tri];
                if (s == 1) lev[a].push_back(e);
                else if (s == 2) rev[a].push_back(e);
            }
            merge_in(lev[a], lnew[a]);
            merge_in(rev[a], rnew[a]);
        }
    }

    std::uint32_t build(const AABB<T>& box, Events ev, std::size_t n, int depth) {
        const auto index = static_cast<std::uint32_t>(out_.nodes.size());
        out_.nodes.emplace_back();
        const Split split = find_split(box, ev, n, depth);
        if (split.axis < 0) {  // leaf
            BuildNode<T>& nd = out_.nodes[index];
            nd.leaf = true;
            nd.prim_begin = static_cast<std::uint32_t>(out_.prims.size());
            for (const Event& e : ev[0])
                if (e.type != Event::end) out_.prims.push_back(e.tri);
            nd.prim_count = static_cast<std::uint32_t>(out_.prims.size() - nd.prim_begin);
            return index;
        }
        const int k = split.axis;
        classify(ev[k], split);
        AABB<T> lbox = box, rbox = box;
        lbox.hi[k] = split.plane;
        rbox.lo[k] = split.plane;
        Events lev, rev;
        std::size_t nl = 0, nr = 0;
        split_events(ev, k, lbox, rbox, lev, rev, nl, nr);
        ev = Events{};  // free the parent's events before recursing

        const std::uint32_t l = build(lbox, std::move(lev), nl, depth + 1);
        const std::uint32_t r = build(rbox, std::move(rev), nr, depth + 1);
        BuildNode<T>& nd = out_.nodes[index];
        nd.leaf = false;
        nd.axis = static_cast<std::uint8_t>(k);
        nd.plane[0] = split.plane;
        nd.plane[1] = split.plane;
        nd.left = l;
        nd.right = r;
        return index;
    }

    static AABB<T> to_t(const AABB<double>& b, const AABB<T>& cell) {
        AABB<T> r;
        for (int a = 0; a < 3; ++a) {
            r.lo[a] = std::clamp(round_down<T>(b.lo[a]), cell.lo[a], cell.hi[a]);
            r.hi[a] = std::clamp(round_up<T>(b.hi[a]), cell.lo[a], cell.hi[a]);
        }
        return r;
    }

    static void merge_in(std::vector<Event>& dst, std::vector<Event>& extra) {
        if (extra.empty()) return;
        std::sort(extra.begin(), extra.end());
        const auto mid = static_cast<std::ptrdiff_t>(dst.size());
        dst.insert(dst.end(), extra.begin(), extra.end());
        std::inplace_merge(dst.begin(), dst.begin() + mid, dst.end());
    }

    std::span<const TriangleVertices<T>> tris_;
    KdBuildOptions opt_;
    int max_depth_ = 56;
    std::vector<std::uint8_t> side_;
    BuiltTree<T> out_;
};

}  // namespace detail

/// SAH kd-tree builder policy (TreeBuilder).
template <Scalar T>
struct KdTreeBuilder {
    using scalar_type = T;        ///< Precision of the input vertices and planes.
    using node_type = KdNode<T>;  ///< Traversed in these nodes (tree.hpp).
    static constexpr TreeKind kind = TreeKind::kd;  ///< Makes kd-trees (one plane per node).
    KdBuildOptions options{};     ///< SAH constants and depth limit.

    /// Builds the SAH kd-tree over `tris` (unhittable triangles left out), O(N log N).
    /// Throws Error when `options` lie outside their documented ranges.
    BuiltTree<T> build(std::span<const TriangleVertices<T>> tris) const {
        return detail::KdBuild<T>(tris, options).run();
    }
};

}  // namespace glint
