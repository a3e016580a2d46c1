// glint/intersection/triangle.hpp: what every ray-triangle test provides, and the two
// containers that use them: Triangle<P> (one triangle in world space) and
// TriangleStore<P> (blocks of triangles stored as an array of structures of arrays: 8
// records per block, field by field, for tree leaves and brute force).
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
#include <bit>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <new>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#if defined(__AVX__)
#include <immintrin.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <glint/core/aabb.hpp>
#include <glint/core/cache_line_allocator.hpp>
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

/// Number of records a batch kernel call processes at most (the size of its output arrays),
/// and the number of records in one block of a TriangleStore's array of structures of
/// arrays.
inline constexpr std::size_t batch_width = 8;

/// Read-only view of `count` records stored as an array of structures of arrays: records
/// are grouped in blocks of batch_width, and a block holds its records' field 0 for all
/// lanes, then field 1, and so on (field k of record i is at
/// data[(i / W) * W * F + k * W + i % W], W = batch_width). So the records a batch kernel
/// reads (one block) are one contiguous run of F * W scalars, a few cache lines, instead of
/// F lines from F separate arrays; for the 128k-triangle knot's 12 MB of records that is
/// what decides how many misses a leaf costs.
template <class T, int F>
struct SoaView {
    const T* data = nullptr;
    std::size_t count = 0;
    /// Field k of record i; the records from i to the end of i's block follow at stride 1.
    const T* field(int k, std::size_t i) const {
        return data + (i / batch_width) * (batch_width * F) + std::size_t(k) * batch_width + i % batch_width;
    }
};

/// Everything a composite (tree leaf, brute force) needs from a ray-triangle test.
///
/// - `P::build(v0, v1, v2)` makes the record from vertices given (in double precision) in
///   the record's frame; it never fails: a degenerate triangle gives a record that never
///   hits.
/// - `P::prepare(ray)` makes per-ray data (for example the watertight test's shear),
///   computed once per ray and frame.
/// - `P::test(x, rd, t, u, v)`: the test itself, written once: x holds one record's
///   field_count scalars (in the order store() writes them, or as P::select_fields(in, rd,
///   out) reorders them for this ray when P has it); true, with t, u, v set, when the ray
///   meets the triangle with t in the open interval (tmin, tmax); NaN or infinite rays give
///   false. Branch-free (bitwise &, selects), so that a loop over lanes vectorizes.
/// - `p.intersect(rd, hit)` and `P::batch(view, first, n, rd, t, u, v)`: the scalar and the
///   batch paths, both made of P::test (detail::test_record, detail::test_lanes). batch
///   tests records first .. first+n-1, which lie in one block of the view (first %
///   batch_width + n <= batch_width), reading field k from view.field(k, first) at stride
///   1; with n = batch_width known at compile time, as tree leaves call it, the lane loop is
///   straight-line SIMD code; it writes t = +inf for a miss.
/// - `store(out)`, `load(view, i)` and `field_count`: the record's scalars, for the
///   blocked layout.
/// - `uses_frame`: whether records need a frame away from their planes (IVM only).
template <class P>
concept TriangleIntersector =
    Scalar<typename P::scalar_type> &&
    requires(const P p, Vec3d a, const Ray<typename P::scalar_type>& r,
             const typename P::RayData& rd, TriangleHit<typename P::scalar_type>& h,
             SoaView<typename P::scalar_type, P::field_count> view,
             typename P::scalar_type* out, typename P::scalar_type& s,
             const typename P::scalar_type (&x)[P::field_count]) {
        { P::name } -> std::convertible_to<const char*>;
        { P::uses_frame } -> std::convertible_to<bool>;
        { P::build(a, a, a) } -> std::same_as<P>;
        { P::prepare(r) } -> std::same_as<typename P::RayData>;
        { P::test(x, rd, s, s, s) } -> std::same_as<bool>;
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

/// The lane of the smallest of W = batch_width values below `limit` (the first such lane
/// on ties), or -1 when none is: how a leaf picks its nearest hit from a batch's t values
/// (+inf for a miss, never NaN). One SIMD compare and a shuffle reduction for 8 floats with
/// AVX; the portable loop (a chain of dependent scalar compares) otherwise.
template <class T>
int nearest_lane(const T* ts, T limit) {
#if defined(__AVX__)
    if constexpr (std::is_same_v<T, float> && batch_width == 8) {
        const __m256 t = _mm256_loadu_ps(ts);
        const int below = _mm256_movemask_ps(_mm256_cmp_ps(t, _mm256_set1_ps(limit), _CMP_LT_OQ));
        if (below == 0) return -1;
        __m256 m = _mm256_min_ps(t, _mm256_permute2f128_ps(t, t, 1));
        m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
        m = _mm256_min_ps(m, _mm256_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
        return std::countr_zero(unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t, m, _CMP_EQ_OQ)) & below));
    }
#endif
    int best = -1;
    for (std::size_t k = 0; k < batch_width; ++k)
        if (ts[k] < limit && (best < 0 || ts[k] < ts[best])) best = int(k);
    return best;
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

/// Pointers to the fields P::test reads, in its order, from pointers `in` to the
/// record's fields in store() order: the identity, or P::select_fields for a policy that
/// picks fields by the ray (the watertight test's axes), once per ray and run of lanes.
template <class P, int F = P::field_count>
[[gnu::always_inline]] inline void test_fields(const typename P::scalar_type* const (&in)[F],
                                               const typename P::RayData& r,
                                               const typename P::scalar_type* (&out)[F]) {
    if constexpr (requires { P::select_fields(in, r, out); }) P::select_fields(in, r, out);
    else
        for (int k = 0; k < F; ++k) out[k] = in[k];
}

/// The scalar path: P::test on one record.
template <class P>
[[gnu::always_inline]] inline bool test_record(const P& p, const typename P::RayData& r,
                                               TriangleHit<typename P::scalar_type>& hit) {
    using T = typename P::scalar_type;
    constexpr int F = P::field_count;
    T x[F];
    if constexpr (requires(const T* const (&in)[F], const T* (&out)[F]) { P::select_fields(in, r, out); }) {
        T stored[F];
        p.store(stored);
        const T* in[F];
        const T* f[F];
        for (int k = 0; k < F; ++k) in[k] = stored + k;
        P::select_fields(in, r, f);
        for (int k = 0; k < F; ++k) x[k] = *f[k];
    } else {
        p.store(x);
    }
    T t, u, v;
    const bool ok = P::test(x, r, t, u, v);
    if (ok) {
        hit.t = t;
        hit.u = u;
        hit.v = v;
    }
    return ok;
}

/// The batch path: P::test on lanes first .. first+n-1 of one block of a SoaView, one
/// lane per iteration of a loop the compiler vectorizes; t = +inf for a miss.
template <class P>
[[gnu::always_inline]] inline void test_lanes(const SoaView<typename P::scalar_type, P::field_count>& view,
                                              std::size_t first, std::size_t n, const typename P::RayData& r,
                                              typename P::scalar_type* ts, typename P::scalar_type* us,
                                              typename P::scalar_type* vs) {
    using T = typename P::scalar_type;
    constexpr int F = P::field_count;
    const T* in[F];
    const T* f[F];
    for (int k = 0; k < F; ++k) in[k] = view.field(k, first);
    test_fields<P>(in, r, f);
    for (std::size_t i = 0; i < n; ++i) {
        T x[F];
        for (int k = 0; k < F; ++k) x[k] = f[k][i];
        T t, u, v;
        const bool ok = P::test(x, r, t, u, v);
        ts[i] = ok ? t : infinity<T>;
        us[i] = u;
        vs[i] = v;
    }
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

/// Blocks of triangle records, stored as an array of structures of arrays (SoaView). A
/// block (one tree leaf, or a whole mesh for brute force) is a range of *groups*; a group is
/// a contiguous run of records sharing one frame origin. Non-IVM policies have exactly one
/// group per block at the world origin; IVM blocks are split until every triangle has a
/// well-conditioned frame (detail::min_frame_quality), which for leaves of a few triangles
/// is almost always one group.
///
/// `add_block(..., Padding::batches)` starts every group of the block on a batch boundary
/// and fills the rest of its last batch with records that never hit (a degenerate triangle:
/// every policy's build() gives it a record that misses), so that a caller may test the
/// group in whole batches with the kernel's full width: tree leaves do. Unpadded blocks
/// (the default) keep records back to back, as brute force and one-triangle blocks want.
/// Queries (closest_hit, any_hit, test_*) are const and thread-safe; add_block is not.
template <TriangleIntersector P>
class TriangleStore {
public:
    using T = typename P::scalar_type;
    static constexpr int F = P::field_count;
    static constexpr std::size_t W = batch_width;

    struct Group {
        Vec3<T> origin;
        std::uint32_t begin, end;  // record range (without padding)
    };
    struct BlockRef {
        std::uint32_t group_begin = 0, group_end = 0;
    };
    enum class Padding { none, batches };

    /// Appends one block; `ids[i]` is reported for hits on `tris[i]` (the original
    /// triangle index, for shading). Returns the block's group range.
    BlockRef add_block(std::span<const TriangleVertices<T>> tris, std::span<const std::uint32_t> ids,
                       Padding padding = Padding::none) {
        if (tris.size() != ids.size())
            throw Error("TriangleStore::add_block: " + std::to_string(tris.size()) +
                        " triangles but " + std::to_string(ids.size()) + " ids");
        BlockRef ref{static_cast<std::uint32_t>(groups_.size()), 0};
        if (!tris.empty()) add_groups(tris, ids, padding == Padding::batches);
        ref.group_end = static_cast<std::uint32_t>(groups_.size());
        return ref;
    }

    /// Number of record slots stored (triangles plus the padding of padded blocks).
    std::size_t size() const { return ids_.size(); }
    std::size_t group_count() const { return groups_.size(); }
    const Group& group(std::size_t g) const { return groups_[g]; }
    std::uint32_t id(std::size_t record) const { return ids_[record]; }
    std::size_t bytes() const {
        return data_.size() * sizeof(T) + ids_.size() * sizeof(std::uint32_t) + groups_.size() * sizeof(Group);
    }
    P record(std::size_t i) const { return P::load(view(), i); }

    SoaView<T, F> view() const { return {data_.data(), ids_.size()}; }

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

    /// Records first .. end-1 of a padded group (`first` on a batch boundary, the last batch
    /// filled with records that never hit), in whole batches, for a ray prepared in the
    /// group's frame; updates `hit` when a hit nearer than hit.t is found, with hit.id the
    /// *record* index (the caller maps the final one by id(): looking up every intermediate
    /// hit's id cost a cache miss each, 11% of the wide BVH's leaf time on incoherent rays).
    /// The leaf test of every tree (kd-tree, BIH, wide BVH).
    template <bool Any>
    [[gnu::always_inline]] bool test_batches(std::uint32_t first, std::uint32_t end, const typename P::RayData& rd,
                                             StoreHit<T>& hit) const {
        const SoaView<T, F> v = view();
        T ts[W], us[W], vs[W];
        bool found = false;
        for (; first < end; first += std::uint32_t(W)) {
            P::batch(v, first, W, rd, ts, us, vs);
            const int best = detail::nearest_lane(ts, hit.t);
            if (best >= 0) {
                if constexpr (Any) return true;
                hit.t = ts[best];
                hit.u = us[best];
                hit.v = vs[best];
                hit.id = first + std::uint32_t(best);
                found = true;
            }
        }
        return found;
    }
    /// Groups first .. first+count-1 of padded blocks, each tested in its own frame with
    /// the interval (ray.tmin, min(ray.tmax, hit.t)).
    template <bool Any>
    bool test_groups(std::uint32_t first, std::uint32_t count, const Ray<T>& ray, StoreHit<T>& hit) const {
        bool found = false;
        for (const std::uint32_t end = first + count; first < end; ++first) {
            const Group& g = groups_[first];
            Ray<T> local = ray;
            local.origin -= g.origin;
            local.tmax = hit.t < ray.tmax ? hit.t : ray.tmax;  // keeps a NaN tmax (no hit)
            if (test_batches<Any>(g.begin, g.end, P::prepare(local), hit)) {
                if constexpr (Any) return true;
                found = true;
            }
        }
        return found;
    }

    /// A tree leaf: `count` groups from `first` for intersectors with frames (IVM), else
    /// `count` padded records from `first` in the world frame, tested with `world`, the ray
    /// prepared once per query.
    template <bool Any>
    bool test_leaf(std::uint32_t first, std::uint32_t count, const Ray<T>& ray, const typename P::RayData& world,
                   StoreHit<T>& hit) const {
        if constexpr (P::uses_frame) return test_groups<Any>(first, count, ray, hit);
        else return test_batches<Any>(first, first + count, world, hit);
    }

private:
    /// Appends one record (its scalars) with its id, opening a new block when needed.
    void push(const T* scalars, std::uint32_t id) {
        const std::size_t i = ids_.size();
        if (i % W == 0) data_.resize(data_.size() + W * F, T(0));
        T* block = data_.data() + (i / W) * (W * F) + i % W;
        for (int k = 0; k < F; ++k) block[std::size_t(k) * W] = scalars[k];
        ids_.push_back(id);
    }
    /// Fills the current block with never-hit records up to the next batch boundary.
    void pad(const Vec3d& p) {
        T scalars[F];
        P::build(p, p, p).store(scalars);
        while (ids_.size() % W != 0) push(scalars, std::numeric_limits<std::uint32_t>::max());
    }

    void add_groups(std::span<const TriangleVertices<T>> tris, std::span<const std::uint32_t> ids, bool padded) {
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
                add_groups(st.first(half), si.first(half), padded);
                add_groups(st.subspan(half), si.subspan(half), padded);
                return;
            }
        }
        const Vec3<T> o(origin);
        const Vec3d od(o);  // the frame origin exactly as rays will be translated by it
        const Vec3d corner = Vec3d(tris[0][0]) - od;
        if (padded) pad(corner);
        Group g{o, static_cast<std::uint32_t>(ids_.size()), 0};
        T scalars[F];
        for (std::size_t i = 0; i < tris.size(); ++i) {
            const P rec = P::build(Vec3d(tris[i][0]) - od, Vec3d(tris[i][1]) - od,
                                   Vec3d(tris[i][2]) - od);
            rec.store(scalars);
            push(scalars, ids[i]);
        }
        g.end = static_cast<std::uint32_t>(ids_.size());
        if (padded) pad(corner);
        groups_.push_back(g);
    }

    template <bool Any>
    bool traverse(BlockRef b, const Ray<T>& ray, StoreHit<T>& hit) const {
        const SoaView<T, F> v = view();
        Ray<T> local = ray;
        local.tmax = std::min(ray.tmax, hit.t);
        bool found = false;
        T ts[W], us[W], vs[W];
        for (std::uint32_t gi = b.group_begin; gi < b.group_end; ++gi) {
            const Group& g = groups_[gi];
            local.origin = ray.origin - g.origin;
            const auto rd = P::prepare(local);
            // Batches end at block boundaries: an unpadded group may start mid-block.
            for (std::size_t first = g.begin, n; first < g.end; first += n) {
                n = std::min<std::size_t>(W - first % W, g.end - first);
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

    std::vector<T, detail::CacheLineAllocator<T>> data_;  // blocks of W records x F fields
    std::vector<std::uint32_t> ids_;
    std::vector<Group> groups_;
};

}  // namespace glint
