// glint/intersection/triangle.hpp: the containers of triangle records: Triangle<P> (one
// triangle in world space) and TriangleStore<P> (blocks of triangles stored as an array of
// structures of arrays: 8 records per block, field by field, for tree leaves and brute
// force). P is a TriangleIntersector (intersector.hpp); its records live in P's frame
// (frame.hpp), which the containers call at every step.
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <new>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include <glint/core/isa.hpp>
#if GLINT_X86
#include <immintrin.h>
#endif

#include <glint/core/aabb.hpp>
#include <glint/core/cache_line_allocator.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/frame.hpp>
#include <glint/intersection/intersector.hpp>

namespace glint {

namespace detail {


/// The lane of the smallest of W = batch_width values below `limit` (the first such lane
/// on ties), or -1 when none is: how a leaf picks its nearest hit from a batch's t values
/// (+inf for a miss, never NaN). On x86-64, two SSE compares and a shuffle reduction for 8
/// floats (SSE2 is always there, and where AVX2 kernels run the compiler encodes them with
/// VEX); the portable loop (a chain of dependent scalar compares) otherwise.
template <class T>
[[gnu::always_inline]] inline int nearest_lane(const T* ts, T limit) {
#if GLINT_X86
    if constexpr (std::is_same_v<T, float> && batch_width == 8) {
        const __m128 a = _mm_loadu_ps(ts), b = _mm_loadu_ps(ts + 4), lim = _mm_set1_ps(limit);
        const int below = _mm_movemask_ps(_mm_cmplt_ps(a, lim)) | _mm_movemask_ps(_mm_cmplt_ps(b, lim)) << 4;
        if (below == 0) return -1;
        __m128 m = _mm_min_ps(a, b);
        m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
        m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
        const int equal = _mm_movemask_ps(_mm_cmpeq_ps(a, m)) | _mm_movemask_ps(_mm_cmpeq_ps(b, m)) << 4;
        return std::countr_zero(unsigned(equal & below));
    }
#endif
    int best = -1;
    for (std::size_t k = 0; k < batch_width; ++k)
        if (ts[k] < limit && (best < 0 || ts[k] < ts[best])) best = int(k);
    return best;
}

}  // namespace detail

/// One triangle in world space: the record and its frame origin (0 in the IdentityFrame,
/// where translating a ray compiles away). This is the convenient single-triangle API;
/// blocks of triangles belong in a TriangleStore, which shares one frame among many records.
template <TriangleIntersector P>
class Triangle {
public:
    using T = typename P::scalar_type;  ///< float or double, P's precision.
    using Frame = FrameOf<P>;           ///< Where the record lives (frame.hpp).

    /// Chooses the frame for (v0, v1, v2), world space, and builds the record relative to it
    /// in double precision; a degenerate triangle gives a record that never hits.
    Triangle(const Vec3<T>& v0, const Vec3<T>& v1, const Vec3<T>& v2) {
        const TriangleVertices<T> tri{v0, v1, v2};
        double quality;
        const Vec3d o = Frame::template choose<T>(std::span(&tri, 1), quality);
        frame_ = Vec3<T>(o);
        record_ = P::build(Vec3d(v0) - o, Vec3d(v1) - o, Vec3d(v2) - o);
    }

    /// Closest hit with t in (ray.tmin, ray.tmax), in world units.
    bool intersect(const Ray<T>& ray, TriangleHit<T>& hit) const {
        return intersect_record(record_, P::prepare(Frame::local(ray, frame_)), hit);
    }

    const P& record() const { return record_; }  ///< The intersector's record, in the frame's coordinates.
    Vec3<T> frame_origin() const { return frame_; }  ///< World position of the frame origin (0 in the IdentityFrame).

private:
    P record_{};
    Vec3<T> frame_{0};
};

/// Closest hit found in a TriangleStore: hit data plus the caller's triangle id.
template <class T>
struct StoreHit : TriangleHit<T> {
    std::uint32_t id = std::numeric_limits<std::uint32_t>::max();  ///< Caller's triangle id; UINT32_MAX: no hit yet.
    /// Whether a hit has been stored (a query found one).
    bool found() const { return id != std::numeric_limits<std::uint32_t>::max(); }
};

/// Blocks of triangle records, stored as an array of structures of arrays (SoaView). A
/// block (one tree leaf, or a whole mesh for brute force) is a range of *groups*; a group is
/// a contiguous run of records sharing one frame origin (frame.hpp). In the IdentityFrame a
/// block is one group at the world origin; with OffsetFrames (IVM) blocks are split until
/// every triangle has a well-conditioned frame, which for leaves of a few triangles is
/// almost always one group.
///
/// `add_block(..., Padding::batches)` starts every group of the block on a batch boundary
/// and fills the rest of its last batch with records that never hit (a degenerate triangle:
/// every policy's build() gives it a record that misses), so that a caller may test the
/// group in whole batches with the kernel's full width: tree leaves do. Unpadded blocks
/// (the default) keep records back to back, as brute force and one-triangle blocks want.
/// Queries (closest_hit, any_hit, test_*) are const and thread-safe; adding is not.
template <TriangleIntersector P>
class TriangleStore {
public:
    using T = typename P::scalar_type;       ///< float or double, P's precision.
    using Frame = FrameOf<P>;                ///< Where the records live (frame.hpp).
    using RayData = RayDataOf<P>;            ///< Per-ray data of P::prepare.
    static constexpr int F = field_count<P>; ///< Scalars per record.
    static constexpr std::size_t W = batch_width;  ///< Records per block of the SoA array.

    /// A run of records sharing one frame origin.
    struct Group {
        Vec3<T> origin;            ///< Frame origin, world space, rounded to T.
        /// First record of the range (without padding).
        std::uint32_t begin, end;  ///< One past the last record of the range (without padding).
    };
    /// A block as add_block returns it: the half-open range of its groups.
    struct BlockRef {
        /// First group of the block.
        std::uint32_t group_begin = 0, group_end = 0;  ///< One past the block's last group.
    };
    /// Whether add_block pads every group to whole batches (tree leaves) or not (the default).
    enum class Padding { none, batches };

    /// Appends one block; `ids[i]` is reported for hits on `tris[i]` (the original
    /// triangle index, for shading). Returns the block's group range.
    BlockRef add_block(std::span<const TriangleVertices<T>> tris, std::span<const std::uint32_t> ids,
                       Padding padding = Padding::none) {
        check_ids(tris.size(), ids.size());
        BlockRef ref{static_cast<std::uint32_t>(groups_.size()), 0};
        if (!tris.empty()) add_groups(tris, ids, padding == Padding::batches);
        ref.group_end = static_cast<std::uint32_t>(groups_.size());
        return ref;
    }
    /// Appends one unpadded block in which every triangle gets the frame it would have
    /// alone, a triangle joining the previous one's group where the frame says so: one group
    /// in the IdentityFrame, a group per triangle with OffsetFrames (the best frame each
    /// record can have). What brute force, the reference of the trees, stores.
    BlockRef add_each(std::span<const TriangleVertices<T>> tris, std::span<const std::uint32_t> ids) {
        check_ids(tris.size(), ids.size());
        BlockRef ref{static_cast<std::uint32_t>(groups_.size()), 0};
        for (std::size_t i = 0; i < tris.size(); ++i) {
            // Built as add_block builds a triangle alone (the same code, so the same record
            // bits: the ray-tile engine's per-triangle blocks are compared with these exactly).
            add_groups(tris.subspan(i, 1), ids.subspan(i, 1), false);
            const std::size_t n = groups_.size();
            if (n >= ref.group_begin + 2 && Frame::joins(groups_[n - 2].origin, groups_[n - 1].origin)) {
                groups_[n - 2].end = groups_[n - 1].end;
                groups_.pop_back();
            }
        }
        ref.group_end = static_cast<std::uint32_t>(groups_.size());
        return ref;
    }

    /// Room for `records` record slots (padding included) and `groups` groups in all, so
    /// that adding up to them allocates nothing (a tree sizes its leaves' store once).
    void reserve(std::size_t records, std::size_t groups) {
        data_.reserve(detail::padded(records) * F);
        ids_.reserve(records);
        groups_.reserve(groups);
    }
    /// Number of record slots stored (triangles plus the padding of padded blocks).
    std::size_t size() const { return ids_.size(); }
    std::size_t group_count() const { return groups_.size(); }  ///< Groups of all blocks.
    const Group& group(std::size_t g) const { return groups_[g]; }  ///< Group g; g < group_count(), unchecked.
    /// The id given for record `record` (a record index, as test_batches reports); padding
    /// records carry UINT32_MAX; unchecked.
    std::uint32_t id(std::size_t record) const { return ids_[record]; }
    /// Bytes of records, ids and groups (sizes, not capacities).
    std::size_t bytes() const {
        return data_.size() * sizeof(T) + ids_.size() * sizeof(std::uint32_t) + groups_.size() * sizeof(Group);
    }
    P record(std::size_t i) const { return detail::load_record<P>(view(), i); }  ///< Record i, loaded back bit for bit.

    RecordView<P> view() const { return {data_.data(), ids_.size()}; }  ///< All records, valid until the next add.

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
    /// hit's id costs a cache miss each).
    template <bool Any>
    [[gnu::always_inline]] bool test_batches(std::uint32_t first, std::uint32_t end, const RayData& rd,
                                             StoreHit<T>& hit) const {
        const RecordView<P> v = view();
        T ts[W], us[W], vs[W];
        bool found = false;
        for (; first < end; first += std::uint32_t(W)) {
            if constexpr (Any) detail::batch_inlined<P>(v, first, W, rd, ts, us, vs);  // see batch_inlined
            else detail::batch<P>(v, first, W, rd, ts, us, vs);
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

    /// The leaf reference (first, count) of a padded block, as the frame counts it.
    std::pair<std::uint32_t, std::uint32_t> leaf(BlockRef ref) const { return Frame::leaf(*this, ref); }
    /// Record slots (padding included) that testing leaf (first, count) reads.
    std::uint64_t leaf_records(std::uint32_t first, std::uint32_t count) const {
        return Frame::records(*this, first, count);
    }
    /// A tree leaf (first, count) (see leaf()): each of its groups with the ray in the
    /// group's frame and the interval (ray.tmin, min(ray.tmax, hit.t)); `world` is
    /// P::prepare(ray), made once per query (the IdentityFrame uses it as it is).
    template <bool Any>
    [[gnu::always_inline]] bool test_leaf(std::uint32_t first, std::uint32_t count, const Ray<T>& ray,
                                          const RayData& world, StoreHit<T>& hit) const {
        return Frame::template test_leaf<Any, P>(*this, first, count, ray, world, hit);
    }

private:
    static void check_ids(std::size_t tris, std::size_t ids) {
        if (tris != ids)
            throw Error("TriangleStore::add_block: " + std::to_string(tris) + " triangles but " +
                        std::to_string(ids) + " ids");
    }
    /// Appends one record (its scalars) with its id, opening a new block when needed.
    void push(const P& rec, std::uint32_t id) {
        const auto scalars = detail::fields_of(rec);
        const std::size_t i = ids_.size();
        if (i % W == 0) data_.resize(data_.size() + W * F, T(0));
        T* block = data_.data() + (i / W) * (W * F) + i % W;
        for (std::size_t k = 0; k < std::size_t(F); ++k) block[k * W] = scalars[k];
        ids_.push_back(id);
    }
    /// Appends the record of `tri` in the frame at `origin`.
    void push_triangle(const TriangleVertices<T>& tri, const Vec3d& origin, std::uint32_t id) {
        push(P::build(Vec3d(tri[0]) - origin, Vec3d(tri[1]) - origin, Vec3d(tri[2]) - origin), id);
    }
    /// Fills the current block with never-hit records up to the next batch boundary.
    void pad(const Vec3d& p) {
        const P never = P::build(p, p, p);
        while (ids_.size() % W != 0) push(never, std::numeric_limits<std::uint32_t>::max());
    }

    void add_groups(std::span<const TriangleVertices<T>> tris, std::span<const std::uint32_t> ids, bool padded) {
        double quality;
        const Vec3d origin = Frame::template choose<T>(tris, quality);
        if (quality < detail::min_frame_quality && tris.size() > 1) return split(tris, ids, padded);
        const Vec3d corner = Vec3d(tris[0][0]) - origin;
        if (padded) pad(corner);
        Group g{Vec3<T>(origin), static_cast<std::uint32_t>(ids_.size()), 0};
        for (std::size_t i = 0; i < tris.size(); ++i) push_triangle(tris[i], origin, ids[i]);
        g.end = static_cast<std::uint32_t>(ids_.size());
        if (padded) pad(corner);
        groups_.push_back(g);
    }
    /// Splits at the median centroid along the longest axis, so that each half is
    /// spatially compact and likely to share one good frame.
    void split(std::span<const TriangleVertices<T>> tris, std::span<const std::uint32_t> ids, bool padded) {
        AABB<T> box;
        for (const auto& t : tris) box.extend((t[0] + t[1] + t[2]) / T(3));
        const int axis = box.longest_axis();
        std::vector<std::size_t> order(tris.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        const std::size_t half = tris.size() / 2;
        auto key = [&](std::size_t i) { return tris[i][0][axis] + tris[i][1][axis] + tris[i][2][axis]; };
        std::nth_element(order.begin(), order.begin() + std::ptrdiff_t(half), order.end(),
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
    }

    template <bool Any>
    bool traverse(BlockRef b, const Ray<T>& ray, StoreHit<T>& hit) const {
        const RecordView<P> v = view();
        Ray<T> local = ray;
        local.tmax = std::min(ray.tmax, hit.t);
        bool found = false;
        T ts[W], us[W], vs[W];
        for (std::uint32_t gi = b.group_begin; gi < b.group_end; ++gi) {
            const Group& g = groups_[gi];
            local.origin = Frame::local(ray, g.origin).origin;
            const RayData rd = P::prepare(local);
            // Batches end at block boundaries: an unpadded group may start mid-block.
            for (std::size_t first = g.begin, n; first < g.end; first += n) {
                n = std::min<std::size_t>(W - first % W, g.end - first);
                detail::batch<P>(v, first, n, rd, ts, us, vs);
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
