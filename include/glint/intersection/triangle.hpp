// glint/intersection/triangle.hpp: what every ray-triangle test provides, and the two
// containers that use them: Triangle<P> (one triangle in world space) and
// TriangleStore<P> (blocks of triangles stored structure-of-arrays, for tree leaves and
// brute force).
//
// A policy P (Ivm, MollerTrumbore, Wald, Watertight) is the per-triangle record: the
// precomputed scalars a test needs, built once from three vertices. Records live in a
// *frame*: their vertices are given relative to a frame origin, and rays are translated
// into that frame before the test. Only the IVM test needs this (000 section 4.1 assumes
// that no triangle plane passes through the origin, see ivm.hpp); the other policies use
// the world frame (origin 0), where translation is exact and costs nothing.
#pragma once

#include <algorithm>
#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>

namespace glint {

/// A hit: the ray parameter t and the barycentric coordinates (u, v) of vertices 1 and 2,
/// so the hit point is (1 - u - v) v0 + u v1 + v v2.
template <class T>
struct TriangleHit {
    T t = infinity<T>;
    T u = 0;
    T v = 0;
};

/// The vertices of one triangle.
template <class T>
using TriangleVertices = std::array<Vec3<T>, 3>;

/// Read-only view of `count` records stored as P::field_count arrays of scalars
/// (structure of arrays): field k of record i is fields[k][i].
template <class T, int F>
struct SoaView {
    std::array<const T*, F> fields{};
    std::size_t count = 0;
};

/// Largest number of records a batch kernel call processes (the size of its output arrays).
/// Groups are not padded: padding every leaf of a kd-tree (often 1 to 4 triangles) to 8
/// records cost memory and measured no faster than the kernel's own remainder loop.
inline constexpr std::size_t batch_width = 8;

/// Everything a composite (tree leaf, brute force) needs from a ray-triangle test.
///
/// - `P::build(v0, v1, v2)` makes the record from vertices given (in double precision) in
///   the record's frame; it never fails: a degenerate triangle gives a record that never
///   hits.
/// - `P::prepare(ray)` makes per-ray data (for example the watertight test's shear),
///   computed once per ray and frame.
/// - `p.intersect(rd, hit)`: true and hit filled when the ray meets the triangle with
///   t in the open interval (tmin, tmax). NaN or infinite rays give false, never NaN.
/// - `P::batch(view, first, n, rd, t, u, v)`: the same test for n <= batch_width records
///   of a structure-of-arrays block, branch-free so that the compiler vectorizes it;
///   writes t = +inf for a miss.
/// - `store(out)`, `load(view, i)` and `field_count`: the record's scalars, for the SoA
///   layout.
/// - `uses_frame`: whether records need a frame away from their planes (IVM only).
template <class P>
concept TriangleIntersector =
    Scalar<typename P::scalar_type> &&
    requires(const P p, Vec3d a, const Ray<typename P::scalar_type>& r,
             const typename P::RayData& rd, TriangleHit<typename P::scalar_type>& h,
             SoaView<typename P::scalar_type, P::field_count> view,
             typename P::scalar_type* out) {
        { P::name } -> std::convertible_to<const char*>;
        { P::uses_frame } -> std::convertible_to<bool>;
        { P::build(a, a, a) } -> std::same_as<P>;
        { P::prepare(r) } -> std::same_as<typename P::RayData>;
        { p.intersect(rd, h) } -> std::same_as<bool>;
        { p.store(out) };
        { P::load(view, std::size_t{}) } -> std::same_as<P>;
        { P::batch(view, std::size_t{}, std::size_t{}, rd, out, out, out) };
    };

namespace detail {

/// The degeneracy rule every policy's build() applies: a triangle whose area is below
/// double rounding noise, |e1 x e2| <= 2^-60 * (longest edge)^2 (or with non-finite
/// vertices), has no area to hit, and its record never reports a hit.
inline bool degenerate_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const double edge = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    return !(glm::length(glm::cross(b - a, c - a)) > edge * edge * 0x1p-60);
}

/// Plain ray data (origin, direction, interval), used by every test but the watertight one.
template <class T>
struct PlainRay {
    Vec3<T> o, d;
    T tmin, tmax;
    static PlainRay from(const Ray<T>& r) { return {r.origin, r.direction, r.tmin, r.tmax}; }
};

/// How well a frame origin c suits the IVM of triangle (a, b, c) given relative to world:
/// the distance of c from the triangle's plane divided by (distance to the triangle +
/// triangle size). The IVM's rounding error in barycentrics grows as 1 / quality; 0 means
/// the plane passes through the frame origin. Degenerate triangles (which never hit) get
/// +inf so they do not constrain the choice.
inline double frame_quality(const Vec3d& origin, const Vec3d& a, const Vec3d& b,
                            const Vec3d& c) {
    const Vec3d n = glm::cross(b - a, c - a);
    const double n_len = glm::length(n);
    const double size = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    if (!(n_len > 0.0) || !(size > 0.0) || !std::isfinite(n_len)) return infinity<double>;
    const Vec3d centroid = (a + b + c) / 3.0;
    const double plane_dist = std::abs(glm::dot(n / n_len, origin - a));
    return plane_dist / (glm::length(origin - centroid) + size);
}

/// Quality a frame must reach, else the block is split in two and each half gets its own
/// frame. With quality >= 1/8 the IVM's barycentric error stays within about 8 ulps of the
/// frame's coordinates (measured by tests/test_intersection.cpp).
inline constexpr double min_frame_quality = 1.0 / 8.0;

/// Best frame origin for a set of triangles: among 26 candidates around their bounding box
/// (centre + {-1,0,1}^3 * box diagonal, centre excluded), the one of greatest minimum
/// quality. For a single triangle: its centroid moved off its plane by its size, which has
/// quality 1/2 or more.
template <class T>
Vec3d choose_frame(std::span<const TriangleVertices<T>> tris, double& quality) {
    auto dv = [](const Vec3<T>& p) { return Vec3d(p); };
    if (tris.size() == 1) {
        const Vec3d a = dv(tris[0][0]), b = dv(tris[0][1]), c = dv(tris[0][2]);
        const double size = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
        const Vec3d n = safe_normalize(glm::cross(b - a, c - a), Vec3d(0, 0, 1));
        const Vec3d origin = (a + b + c) / 3.0 + n * (size > 0 ? size : 1.0);
        quality = frame_quality(origin, a, b, c);
        return origin;
    }
    Vec3d lo(infinity<double>), hi(-infinity<double>);
    for (const auto& t : tris)
        for (const auto& p : t) {
            lo = glm::min(lo, dv(p));
            hi = glm::max(hi, dv(p));
        }
    const Vec3d centre = (lo + hi) * 0.5;
    double reach = glm::length(hi - lo);
    if (!(reach > 0.0)) reach = std::max(1.0, glm::length(centre));
    Vec3d best = centre + Vec3d(reach);
    quality = -1.0;
    for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
            for (int k = -1; k <= 1; ++k) {
                if (i == 0 && j == 0 && k == 0) continue;
                const Vec3d cand = centre + Vec3d(i, j, k) * reach;
                double q = infinity<double>;
                for (const auto& t : tris) q = std::min(q, frame_quality(cand, dv(t[0]), dv(t[1]), dv(t[2])));
                if (q > quality) {
                    quality = q;
                    best = cand;
                }
            }
    return best;
}

}  // namespace detail

/// One triangle in world space: the record plus, for IVM, its own frame origin.
/// This is the convenient single-triangle API; blocks of triangles belong in a
/// TriangleStore, which shares one frame among many records.
template <TriangleIntersector P>
class Triangle {
public:
    using T = typename P::scalar_type;

    Triangle(const Vec3<T>& v0, const Vec3<T>& v1, const Vec3<T>& v2) {
        if constexpr (P::uses_frame) {
            const TriangleVertices<T> tri{v0, v1, v2};
            double quality;
            frame_ = Vec3<T>(detail::choose_frame<T>(std::span(&tri, 1), quality));
        }
        const Vec3d o(frame_);
        record_ = P::build(Vec3d(v0) - o, Vec3d(v1) - o, Vec3d(v2) - o);
    }

    /// Closest hit with t in (ray.tmin, ray.tmax), in world units.
    bool intersect(const Ray<T>& ray, TriangleHit<T>& hit) const {
        Ray<T> local = ray;
        if constexpr (P::uses_frame) local.origin -= frame_;
        return record_.intersect(P::prepare(local), hit);
    }

    const P& record() const { return record_; }
    Vec3<T> frame_origin() const { return frame_; }

private:
    P record_{};
    Vec3<T> frame_{0};
};

/// Closest hit found in a TriangleStore: hit data plus the caller's triangle id.
template <class T>
struct StoreHit : TriangleHit<T> {
    std::uint32_t id = std::numeric_limits<std::uint32_t>::max();
};

/// Blocks of triangle records in structure-of-arrays layout. A block (one tree leaf, or a
/// whole mesh for brute force) is a range of *groups*; a group is a contiguous run of
/// records sharing one frame origin. Non-IVM policies have exactly one group per block at
/// the world origin; IVM blocks are split until every triangle has a well-conditioned
/// frame (detail::min_frame_quality), which for leaves of a few triangles is almost
/// always one group.
template <TriangleIntersector P>
class TriangleStore {
public:
    using T = typename P::scalar_type;
    static constexpr int F = P::field_count;

    struct Group {
        Vec3<T> origin;
        std::uint32_t begin, end;  // record range
    };
    struct BlockRef {
        std::uint32_t group_begin = 0, group_end = 0;
    };

    /// Appends one block; `ids[i]` is reported for hits on `tris[i]` (the original
    /// triangle index, for shading). Returns the block's group range.
    BlockRef add_block(std::span<const TriangleVertices<T>> tris,
                       std::span<const std::uint32_t> ids) {
        if (tris.size() != ids.size())
            throw Error("TriangleStore::add_block: " + std::to_string(tris.size()) +
                        " triangles but " + std::to_string(ids.size()) + " ids");
        BlockRef ref{static_cast<std::uint32_t>(groups_.size()), 0};
        if (!tris.empty()) add_groups(tris, ids);
        ref.group_end = static_cast<std::uint32_t>(groups_.size());
        return ref;
    }

    /// Number of triangle records stored.
    std::size_t size() const { return ids_.size(); }
    std::size_t group_count() const { return groups_.size(); }
    const Group& group(std::size_t g) const { return groups_[g]; }
    std::uint32_t id(std::size_t record) const { return ids_[record]; }
    std::size_t bytes() const {
        return ids_.size() * (F * sizeof(T) + sizeof(std::uint32_t)) + groups_.size() * sizeof(Group);
    }
    P record(std::size_t i) const { return P::load(view(), i); }

    SoaView<T, F> view() const {
        SoaView<T, F> v;
        for (int k = 0; k < F; ++k) v.fields[k] = fields_[k].data();
        v.count = ids_.size();
        return v;
    }

    /// Closest hit among the block's records with t in (ray.tmin, hit.t or ray.tmax);
    /// `hit` is updated only when a closer hit is found. Uses the batch kernel.
    bool closest_hit(BlockRef b, const Ray<T>& ray, StoreHit<T>& hit) const {
        return traverse<false>(b, ray, hit);
    }
    /// Any hit with t in (ray.tmin, ray.tmax): for shadow rays.
    bool any_hit(BlockRef b, const Ray<T>& ray) const {
        StoreHit<T> hit;
        return traverse<true>(b, ray, hit);
    }

private:
    void add_groups(std::span<const TriangleVertices<T>> tris, std::span<const std::uint32_t> ids) {
        Vec3d origin(0.0);
        if constexpr (P::uses_frame) {
            double quality;
            origin = detail::choose_frame<T>(tris, quality);
            if (quality < detail::min_frame_quality && tris.size() > 1) {
                // Split at the median centroid along the longest axis, so that each half is
                // spatially compact and likely to share one good frame.
                AABB<T> box;
                for (const auto& t : tris) box.extend((t[0] + t[1] + t[2]) / T(3));
                const int axis = box.longest_axis();
                std::vector<std::size_t> order(tris.size());
                for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
                const std::size_t half = tris.size() / 2;
                auto key = [&](std::size_t i) { return tris[i][0][axis] + tris[i][1][axis] + tris[i][2][axis]; };
                std::nth_element(order.begin(), order.begin() + half, order.end(),
                                 [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
                std::vector<TriangleVertices<T>> sorted_tris;
                std::vector<std::uint32_t> sorted_ids;
                for (std::size_t i : order) {
                    sorted_tris.push_back(tris[i]);
                    sorted_ids.push_back(ids[i]);
                }
                const std::span<const TriangleVertices<T>> st(sorted_tris);
                const std::span<const std::uint32_t> si(sorted_ids);
                add_groups(st.first(half), si.first(half));
                add_groups(st.subspan(half), si.subspan(half));
                return;
            }
        }
        const Vec3<T> o(origin);
        const Vec3d od(o);  // the frame origin exactly as rays will be translated by it
        Group g{o, static_cast<std::uint32_t>(ids_.size()), 0};
        T scalars[F];
        for (std::size_t i = 0; i < tris.size(); ++i) {
            const P rec = P::build(Vec3d(tris[i][0]) - od, Vec3d(tris[i][1]) - od,
                                   Vec3d(tris[i][2]) - od);
            rec.store(scalars);
            for (int k = 0; k < F; ++k) fields_[k].push_back(scalars[k]);
            ids_.push_back(ids[i]);
        }
        g.end = static_cast<std::uint32_t>(ids_.size());
        groups_.push_back(g);
    }

    template <bool Any>
    bool traverse(BlockRef b, const Ray<T>& ray, StoreHit<T>& hit) const {
        const SoaView<T, F> v = view();
        Ray<T> local = ray;
        local.tmax = std::min(ray.tmax, hit.t);
        bool found = false;
        T ts[batch_width], us[batch_width], vs[batch_width];
        for (std::uint32_t gi = b.group_begin; gi < b.group_end; ++gi) {
            const Group& g = groups_[gi];
            local.origin = ray.origin - g.origin;
            const auto rd = P::prepare(local);
            for (std::size_t first = g.begin; first < g.end; first += batch_width) {
                const std::size_t n = std::min<std::size_t>(batch_width, g.end - first);
                P::batch(v, first, n, rd, ts, us, vs);
                // Most blocks have no hit closer than tmax: one cheap test first.
                bool any = false;
                for (std::size_t k = 0; k < n; ++k) any |= ts[k] < local.tmax;
                if (!any) continue;
                if constexpr (Any) return true;
                for (std::size_t k = 0; k < n; ++k) {
                    if (ts[k] < local.tmax) {
                        local.tmax = ts[k];
                        hit.t = ts[k];
                        hit.u = us[k];
                        hit.v = vs[k];
                        hit.id = ids_[first + k];
                        found = true;
                    }
                }
            }
        }
        return found;
    }

    std::array<std::vector<T>, F> fields_;
    std::vector<std::uint32_t> ids_;
    std::vector<Group> groups_;
};

}  // namespace glint
