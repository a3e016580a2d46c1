// glint/occluders/visibility.hpp: point-to-point visibility policies for gathering from
// point lights (VPLs): exact shadow rays through a ray accelerator (ShadowRayVisibility), and
// the approximate tests against occluder spheres of Szécsi 2009, ch. 5.
//
// Szécsi 2009, §5.1: for a shading point x, each sphere (c, R) is pre-processed into the unit
// direction u = (c - x) / t, t = |c - x|, and cos gamma = sqrt(t^2 - R^2) / t (the half-angle
// of the cone from x that contains the sphere). A point light y at distance q = |y - x| in
// direction l is occluded by the sphere when cos delta = u . l > cos gamma and q > t
// ("slightly bent, view-dependent occluder disks": the light is compared with the centre's
// distance, not the sphere's surface).
// Szécsi 2009, §5.3.1: spheres entirely behind the tangent plane of x (u . n t <= -R) are
// culled, and so are spheres farther than the light (t >= q, the same comparison); the rest
// are scanned linearly (SphereVisibilityLinear) or searched in a kd-tree
// (SphereVisibilityKdTree) built by object-median splits, which the dissertation found to
// overtake the linear scan at about 800 spheres.
// Szécsi 2009, §5.3.2: the self-shadowing heuristic excludes spheres whose centre is closer
// to x than twice their radius (t < 2R; factor configurable).
// A point x inside a sphere (t <= R, only without the heuristic) is occluded from every
// light farther than the centre.
//
// Both sphere searches evaluate the same per-sphere predicate (detail::occluder_view and
// detail::occludes), so they agree exactly; the kd-tree computes a sphere's view lazily the
// first time a light's segment reaches it for the current shading point.
// Visibility policies (concept VisibilityPolicy) are stateful per thread: set_point(x, n),
// then visible(y) for every light.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/occluders/spheres.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// A visibility policy: set_point(x, n) once per shading point, then visible(y) per light.
template <class V, class T>
concept VisibilityPolicy = requires(V v, const Vec3<T>& p) {
    { v.set_point(p, p) };
    { v.visible(p) } -> std::same_as<bool>;
};

/// A visibility policy that also tests many lights from the shading point in one call:
/// visible(ys, out) sets out[i] = visible(ys[i]).
template <class V, class T>
concept BatchVisibilityPolicy = VisibilityPolicy<V, T> && requires(V v, std::span<const Vec3<T>> ys, std::span<bool> out) {
    v.visible(ys, out);
};

/// out[i] = vis.visible(ys[i]) for every i (the same size): the policy's batch test where it
/// has one, a light at a time otherwise.
template <class T, class V>
    requires VisibilityPolicy<V, T>
void visible_all(V& vis, std::span<const Vec3<T>> ys, std::span<bool> out) {
    if constexpr (BatchVisibilityPolicy<V, T>) {
        vis.visible(ys, out);
    } else {
        for (std::size_t i = 0; i < ys.size(); ++i) out[i] = vis.visible(ys[i]);
    }
}

/// Exact visibility: a shadow ray through a RayAccelerator (trees/, BruteForce) from x, moved
/// `epsilon` along n off its surface, to just short of y (a fraction epsilon of the segment).
/// A batch of lights goes as one stream of shadow rays (any_hits(): MeshBvh's packets).
template <RayAccelerator Accel>
class ShadowRayVisibility {
public:
    using T = typename Accel::scalar_type;  ///< Accel's scalar type.
    /// Keeps a pointer to `accel` (it must outlive this); `epsilon`: offset along n, world
    /// units, and the fraction of the segment left out before y.
    ShadowRayVisibility(const Accel& accel, T epsilon) : accel_(&accel), eps_(epsilon) {}
    void set_point(const Vec3<T>& x, const Vec3<T>& n) { x_ = x + eps_ * n; }  ///< Shading point x, its unit normal n.
    /// Whether no triangle lies between x and y (one any-hit query).
    bool visible(const Vec3<T>& y) const { return !accel_->any_hit(ray_to(y)); }
    /// out[i] = visible(ys[i]) (the same size), as one stream of shadow rays.
    void visible(std::span<const Vec3<T>> ys, std::span<bool> out) {
        rays_.resize(ys.size());
        for (std::size_t i = 0; i < ys.size(); ++i) rays_[i] = ray_to(ys[i]);
        any_hits(*accel_, std::span<const Ray<T>>(rays_), out);
        for (bool& o : out) o = !o;
    }

private:
    // Ray parameter in units of |y - x|: y itself is on a surface.
    Ray<T> ray_to(const Vec3<T>& y) const { return Ray<T>{x_, y - x_, T(0), T(1) - eps_}; }

    const Accel* accel_;
    T eps_;
    Vec3<T> x_{0};
    std::vector<Ray<T>> rays_;  // the batch's shadow rays (scratch)
};

/// Culling options shared by the sphere visibility policies.
template <Scalar T>
struct SphereVisibilityOptions {
    bool self_shadow_heuristic = true;  ///< Skip spheres whose centre is nearer x than factor * radius.
    T self_shadow_factor = T(2);  ///< Multiple of the radius the heuristic uses; Szécsi 2009, §5.3.2: "the double of their radius".
};

namespace detail {

/// Per-shading-point view of one sphere; false when the sphere is culled (behind the
/// tangent plane, or excluded by the self-shadowing heuristic).
template <class T>
inline bool occluder_view(const Sphere<T>& s, const Vec3<T>& x, const Vec3<T>& n, const SphereVisibilityOptions<T>& o,
                          Vec3<T>& u, T& cos_gamma, T& t) {
    const Vec3<T> v = s.centre - x;
    if (glm::dot(v, n) <= -s.radius) return false;
    const T t2 = glm::dot(v, v);
    t = std::sqrt(t2);
    if (o.self_shadow_heuristic && t < o.self_shadow_factor * s.radius) return false;
    if (t <= s.radius) {
        u = n;
        cos_gamma = T(-2);  // inside the sphere: every direction
        return true;
    }
    u = v / t;
    cos_gamma = std::sqrt(t2 - s.radius * s.radius) / t;
    return true;
}

template <class T>
inline bool occludes(const Vec3<T>& u, T cos_gamma, T t, const Vec3<T>& l, T q) {
    return t < q && u.x * l.x + u.y * l.y + u.z * l.z > cos_gamma;
}

}  // namespace detail

/// Linear scan over the spheres that survive culling at the shading point (Szécsi 2009, §5.3.1).
template <Scalar T>
class SphereVisibilityLinear {
public:
    /// Copies `spheres`. Throws Error for a non-finite centre or radius, or a negative radius.
    explicit SphereVisibilityLinear(std::span<const Sphere<T>> spheres, SphereVisibilityOptions<T> opt = {})
        : s_(spheres.begin(), spheres.end()), opt_(opt) {
        for (const auto& s : s_)
            if (!all_finite(s.centre) || !(s.radius >= 0) || !std::isfinite(s.radius))
                throw Error("glint::SphereVisibilityLinear: sphere with non-finite centre or radius");
        const std::size_t n = (s_.size() + block - 1) / block * block;
        ux_.resize(n), uy_.resize(n), uz_.resize(n), cg_.resize(n), t_.resize(n);
    }

    /// Pre-processes every sphere for shading point x with unit normal n (no allocation).
    void set_point(const Vec3<T>& x, const Vec3<T>& n) {
        x_ = x;
        count_ = 0;
        for (const auto& s : s_) {
            Vec3<T> u;
            T cg, t;
            if (!detail::occluder_view(s, x, n, opt_, u, cg, t)) continue;
            ux_[count_] = u.x, uy_[count_] = u.y, uz_[count_] = u.z, cg_[count_] = cg, t_[count_] = t;
            ++count_;
        }
        for (std::size_t i = count_; i < (count_ + block - 1) / block * block; ++i)
            ux_[i] = uy_[i] = uz_[i] = cg_[i] = T(0), t_[i] = infinity<T>;
    }

    /// Whether a surviving sphere occludes light y from x; false for y == x. O(active()).
    bool occluded(const Vec3<T>& y) const {
        const Vec3<T> d = y - x_;
        const T q = std::sqrt(glm::dot(d, d));
        if (!(q > T(0))) return false;
        const Vec3<T> l = d / q;
        // Branch-free blocks of 16 (vectorizable), the same predicate as detail::occludes;
        // padding slots have t = +inf and never occlude.
        const T *ux = ux_.data(), *uy = uy_.data(), *uz = uz_.data(), *cg = cg_.data(), *tt = t_.data();
        for (std::size_t b = 0; b < count_; b += block) {
            int hit = 0;
            for (std::size_t i = b; i < b + block; ++i)
                hit |= int(tt[i] < q) & int(ux[i] * l.x + uy[i] * l.y + uz[i] * l.z > cg[i]);
            if (hit) return true;
        }
        return false;
    }
    bool visible(const Vec3<T>& y) const { return !occluded(y); }  ///< Not occluded(y).
    std::size_t active() const { return count_; }  ///< Spheres left after culling at the current point.
    std::size_t size() const { return s_.size(); }  ///< Spheres given.

private:
    static constexpr std::size_t block = 16;
    std::vector<Sphere<T>> s_;
    SphereVisibilityOptions<T> opt_;
    Vec3<T> x_{0};
    std::size_t count_ = 0;
    std::vector<T> ux_, uy_, uz_, cg_, t_;
};

/// Kd-tree search (Szécsi 2009, §5.3.1): object-median kd-tree over the spheres' boxes; a light
/// walks the segment from x to y front to back and tests the spheres of the leaves it meets.
template <Scalar T>
class SphereVisibilityKdTree {
public:
    /// Copies `spheres` and builds the tree, leaves of at most `leaf_size` spheres (0 means 1).
    /// Throws Error for a non-finite centre or radius, or a negative radius.
    explicit SphereVisibilityKdTree(std::span<const Sphere<T>> spheres, SphereVisibilityOptions<T> opt = {},
                                    std::size_t leaf_size = 4)
        : s_(spheres.begin(), spheres.end()), opt_(opt) {
        for (const auto& s : s_) {
            if (!all_finite(s.centre) || !(s.radius >= 0) || !std::isfinite(s.radius))
                throw Error("glint::SphereVisibilityKdTree: sphere with non-finite centre or radius");
            bounds_.extend(box(s));
        }
        const std::size_t n = s_.size();
        stamp_.assign(n, 0);
        view_.resize(n);
        std::vector<std::uint32_t> ids(n);
        std::iota(ids.begin(), ids.end(), 0u);
        nodes_.push_back({});
        if (n) build(0, ids, 0, std::max<std::size_t>(leaf_size, 1));
    }

    /// Shading point x, unit normal n; spheres are pre-processed lazily by occluded(). O(1).
    void set_point(const Vec3<T>& x, const Vec3<T>& n) {
        x_ = x;
        n_ = n;
        if (++epoch_ == 0) {  // wrapped: reset stamps
            std::fill(stamp_.begin(), stamp_.end(), 0u);
            epoch_ = 1;
        }
    }

    /// Whether a sphere occludes light y from x, walking the segment front to back; false for
    /// y == x. Non-const: caches the views of the spheres it meets for the current point.
    bool occluded(const Vec3<T>& y) {
        if (s_.empty()) return false;
        const Vec3<T> d = y - x_;
        const T q = std::sqrt(glm::dot(d, d));
        if (!(q > T(0))) return false;
        const Vec3<T> l = d / q;
        const Vec3<T> inv(T(1) / l.x, T(1) / l.y, T(1) / l.z);
        T t0 = 0, t1 = q;
        for (int a = 0; a < 3; ++a) {
            const T ta = (bounds_.lo[a] - x_[a]) * inv[a], tb = (bounds_.hi[a] - x_[a]) * inv[a];
            const T tn = std::min(ta, tb), tf = std::max(ta, tb);
            if (tn == tn) t0 = std::max(t0, tn);
            if (tf == tf) t1 = std::min(t1, tf);
        }
        if (t0 > t1) return false;
        struct Entry {
            std::uint32_t node;
            T t0, t1;
        };
        Entry stack[64];
        int sp = 0;
        std::uint32_t node = 0;
        for (;;) {
            const Node* nd = &nodes_[node];
            while (!nd->leaf) {
                const int a = nd->axis;
                const T tp = (nd->split - x_[a]) * inv[a];
                const bool below = x_[a] < nd->split || (x_[a] == nd->split && l[a] <= T(0));
                const std::uint32_t near = below ? nd->child : nd->child + 1, far = below ? nd->child + 1 : nd->child;
                if (tp != tp) {  // x on the plane, ray along it: both sides
                    stack[sp++] = {far, t0, t1};
                    node = near;
                } else if (tp > t1 || tp < T(0)) {
                    node = near;
                } else if (tp < t0) {
                    node = far;
                } else {
                    stack[sp++] = {far, tp, t1};
                    t1 = tp;
                    node = near;
                }
                nd = &nodes_[node];
            }
            for (std::uint32_t k = nd->child; k < nd->child + nd->count; ++k) {
                const std::uint32_t i = refs_[k];
                View& v = view_[i];
                if (stamp_[i] != epoch_) {
                    stamp_[i] = epoch_;
                    v.active = detail::occluder_view(s_[i], x_, n_, opt_, v.u, v.cos_gamma, v.t);
                }
                if (v.active && detail::occludes(v.u, v.cos_gamma, v.t, l, q)) return true;
            }
            if (sp == 0) return false;
            const Entry& e = stack[--sp];
            node = e.node;
            t0 = e.t0;
            t1 = e.t1;
        }
    }
    bool visible(const Vec3<T>& y) { return !occluded(y); }  ///< Not occluded(y).
    std::size_t size() const { return s_.size(); }  ///< Spheres given.
    std::size_t node_count() const { return nodes_.size(); }  ///< Tree nodes, leaves included.

private:
    struct Node {
        T split = 0;
        std::uint8_t axis = 0;
        bool leaf = true;
        std::uint32_t child = 0;  // split: left child (right = child + 1); leaf: first ref
        std::uint32_t count = 0;
    };
    struct View {
        Vec3<T> u{0};
        T cos_gamma = 0, t = 0;
        bool active = false;
    };

    /// The sphere's box, widened by a relative margin so that rounding in the traversal's
    /// plane distances cannot skip a sphere whose entry point lies on a split plane.
    static AABB<T> box(const Sphere<T>& s) {
        const T m = s.radius * T(1.001) + T(1e-5) * (std::abs(s.centre.x) + std::abs(s.centre.y) + std::abs(s.centre.z));
        return {s.centre - Vec3<T>(m), s.centre + Vec3<T>(m)};
    }

    void build(std::uint32_t node, std::vector<std::uint32_t>& ids, int depth, std::size_t leaf_size) {
        auto make_leaf = [&] {
            nodes_[node].leaf = true;
            nodes_[node].child = std::uint32_t(refs_.size());
            nodes_[node].count = std::uint32_t(ids.size());
            refs_.insert(refs_.end(), ids.begin(), ids.end());
        };
        if (ids.size() <= leaf_size || depth >= 30) return make_leaf();
        AABB<T> cb;
        for (std::uint32_t i : ids) cb.extend(s_[i].centre);
        const int axis = max_abs_axis(cb.extent());
        const std::size_t mid = ids.size() / 2;
        std::nth_element(ids.begin(), ids.begin() + std::ptrdiff_t(mid), ids.end(),
                         [&](std::uint32_t a, std::uint32_t b) { return s_[a].centre[axis] < s_[b].centre[axis]; });
        const T split = s_[ids[mid]].centre[axis];
        std::vector<std::uint32_t> left, right;
        for (std::uint32_t i : ids) {
            const AABB<T> b = box(s_[i]);
            if (b.lo[axis] <= split) left.push_back(i);
            if (b.hi[axis] >= split) right.push_back(i);
        }
        // Stop where a split would mostly duplicate references (large overlapping spheres):
        // more than 1.6 references per sphere would grow the tree exponentially with depth.
        if (10 * (left.size() + right.size()) > 16 * ids.size()) return make_leaf();
        const auto child = std::uint32_t(nodes_.size());
        nodes_.push_back({});
        nodes_.push_back({});
        nodes_[node].leaf = false;
        nodes_[node].axis = std::uint8_t(axis);
        nodes_[node].split = split;
        nodes_[node].child = child;
        ids.clear();
        ids.shrink_to_fit();
        build(child, left, depth + 1, leaf_size);
        build(child + 1, right, depth + 1, leaf_size);
    }

    std::vector<Sphere<T>> s_;
    SphereVisibilityOptions<T> opt_;
    AABB<T> bounds_;
    std::vector<Node> nodes_;
    std::vector<std::uint32_t> refs_;
    std::vector<std::uint32_t> stamp_;
    std::vector<View> view_;
    std::uint32_t epoch_ = 0;
    Vec3<T> x_{0}, n_{0, 0, 1};
};

}  // namespace glint
