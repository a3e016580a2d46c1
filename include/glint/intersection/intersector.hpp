// glint/intersection/intersector.hpp: what a ray-triangle test provides (the
// TriangleIntersector concept), and what glint derives from it: storing a record as
// scalars, loading it back from blocks of records, and testing one record or a batch of
// them.
//
// A policy P (Ivm, MollerTrumbore, Wald, Watertight, or a user's own) is the per-triangle
// *record*: the precomputed scalars a test needs, built once from three vertices. The
// record is a struct of scalar_type values only (no other types, no padding), so that the
// containers can store it field by field in blocks (SoaView) and load it back bit for bit.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <concepts>
#include <cstddef>
#include <type_traits>
#include <utility>

#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>

namespace glint {

/// A hit: the ray parameter t and the barycentric coordinates (u, v) of vertices 1 and 2,
/// so the hit point is (1 - u - v) v0 + u v1 + v v2.
template <class T>
struct TriangleHit {
    T t = infinity<T>;  ///< Ray parameter of the hit; +inf (the default) means no hit yet.
    T u = 0;            ///< Barycentric weight of vertex 1.
    T v = 0;            ///< Barycentric weight of vertex 2.
};

/// The end of a closest-hit query's interval for a hit found so far: ray.tmax lowered to
/// hit.t (a NaN tmax kept: no hit).
template <class T, class Hit>
[[gnu::always_inline]] inline T tmax_before(const Ray<T>& ray, const Hit& hit) {
    return hit.t < ray.tmax ? hit.t : ray.tmax;
}

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
/// F lines from F separate arrays.
template <class T, int F>
struct SoaView {
    const T* data = nullptr;  ///< First scalar of block 0; not owned.
    std::size_t count = 0;    ///< Records in the view (the last block may be partly filled).
    /// Field k of record i; the records from i to the end of i's block follow at stride 1.
    const T* field(int k, std::size_t i) const {
        return data + (i / batch_width) * (batch_width * F) + std::size_t(k) * batch_width + i % batch_width;
    }
};

/// A ray-triangle test, as the containers (Triangle, TriangleStore, TriangleLeaves, the
/// trees) use it: three members and the scalar type.
///
/// - `P::build(v0, v1, v2)` makes the record from vertices given (in double precision) in
///   the record's frame; it never fails: a degenerate triangle gives a record that never
///   hits.
/// - `P::prepare(ray)` makes the per-ray data (for example the watertight test's shear),
///   computed once per ray and frame; any type.
/// - `p.test(ray_data, t, u, v)`: true, with t, u, v set, when the ray meets the triangle
///   with t in the open interval (tmin, tmax); NaN or infinite rays give false. Written
///   without branches (bitwise &, selects), the batch path's loop over 8 records
///   vectorizes.
///
/// Optional members, found by what they do (none is needed):
/// - `using frame = ...`: where the records live (frame.hpp); without it, IdentityFrame;
/// - `P::select_fields(in, ray_data, out)`: reorders the record's fields for a ray (the
///   watertight test picks vertex coordinates by the ray's axes), once per ray and batch;
/// - `P::batch(view, first, n, ray_data, ts, us, vs)`: a batch kernel of the policy's own
///   (hand-written SIMD, or instrumentation), used instead of detail::test_lanes.
template <class P>
concept TriangleIntersector =
    Scalar<typename P::scalar_type> && std::is_trivially_copyable_v<P> &&
    sizeof(P) % sizeof(typename P::scalar_type) == 0 &&
    requires(const P p, Vec3d a, const Ray<typename P::scalar_type>& r, typename P::scalar_type& s) {
        { P::build(a, a, a) } -> std::same_as<P>;
        { p.test(P::prepare(r), s, s, s) } -> std::same_as<bool>;
    };

/// The number of scalars in a record of P.
template <class P>
inline constexpr int field_count = int(sizeof(P) / sizeof(typename P::scalar_type));

/// The per-ray data of P (what P::prepare returns).
template <class P>
using RayDataOf = decltype(P::prepare(std::declval<const Ray<typename P::scalar_type>&>()));

/// The view of blocks of records of P.
template <class P>
using RecordView = SoaView<typename P::scalar_type, field_count<P>>;

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

/// The record's scalars, in memory order.
template <class P>
[[gnu::always_inline]] inline std::array<typename P::scalar_type, field_count<P>> fields_of(const P& p) {
    return std::bit_cast<std::array<typename P::scalar_type, field_count<P>>>(p);
}

/// Record i of a view.
template <class P>
[[gnu::always_inline]] inline P load_record(const RecordView<P>& view, std::size_t i) {
    std::array<typename P::scalar_type, field_count<P>> x;
    for (int k = 0; k < field_count<P>; ++k) x[std::size_t(k)] = *view.field(k, i);
    return std::bit_cast<P>(x);
}

/// Pointers to the fields P::test reads, in its order, from pointers `in` to the record's
/// fields in memory order: the identity, or P::select_fields for a policy that picks fields
/// by the ray (the watertight test's axes).
template <class P, int F = field_count<P>>
[[gnu::always_inline]] inline void test_fields(const typename P::scalar_type* const (&in)[F],
                                               const RayDataOf<P>& r, const typename P::scalar_type* (&out)[F]) {
    if constexpr (requires { P::select_fields(in, r, out); }) P::select_fields(in, r, out);
    else
        for (int k = 0; k < F; ++k) out[k] = in[k];
}

/// The record of P made of the scalars at `f[k][i]`.
template <class P, int F = field_count<P>>
[[gnu::always_inline]] inline P gather(const typename P::scalar_type* const (&f)[F], std::size_t i) {
    std::array<typename P::scalar_type, F> x;
    for (int k = 0; k < F; ++k) x[std::size_t(k)] = f[k][i];
    return std::bit_cast<P>(x);
}

/// The portable batch path: P::test on lanes first .. first+n-1 of one block of a view,
/// one lane per iteration of a loop the compiler vectorizes; t = +inf for a miss.
template <class P>
[[gnu::always_inline]] inline void test_lanes(const RecordView<P>& view, std::size_t first, std::size_t n,
                                              const RayDataOf<P>& r, typename P::scalar_type* ts,
                                              typename P::scalar_type* us, typename P::scalar_type* vs) {
    using T = typename P::scalar_type;
    constexpr int F = field_count<P>;
    const T* in[F];
    const T* f[F];
    for (int k = 0; k < F; ++k) in[k] = view.field(k, first);
    test_fields<P>(in, r, f);
    for (std::size_t i = 0; i < n; ++i) {
        T t, u, v;
        const bool ok = gather<P>(f, i).test(r, t, u, v);
        ts[i] = ok ? t : infinity<T>;
        us[i] = u;
        vs[i] = v;
    }
}

/// The batch path the containers call: records first .. first+n-1, which lie in one block
/// of the view (first % batch_width + n <= batch_width); with n = batch_width known at
/// compile time, as tree leaves call it, the lane loop is straight-line SIMD code. P's own
/// `batch` where it has one, else test_lanes. batch_inlined is the same, always inlined: the
/// any-hit leaf tests use it (GCC 12, -O3 -march=native, otherwise called a clone of batch once
/// per leaf from MeshBvh::any_hit, which ran 2.5 times slower); closest-hit leaf tests keep the
/// compiler's choice (forcing it there cost the 8-wide BVH 12-28% on primary rays).
template <class P>
[[gnu::always_inline]] inline void batch_inlined(const RecordView<P>& view, std::size_t first, std::size_t n,
                                                 const RayDataOf<P>& r, typename P::scalar_type* ts,
                                                 typename P::scalar_type* us, typename P::scalar_type* vs) {
    if constexpr (requires { P::batch(view, first, n, r, ts, us, vs); }) P::batch(view, first, n, r, ts, us, vs);
    else test_lanes<P>(view, first, n, r, ts, us, vs);
}
template <class P>
inline void batch(const RecordView<P>& view, std::size_t first, std::size_t n, const RayDataOf<P>& r,
                  typename P::scalar_type* ts, typename P::scalar_type* us, typename P::scalar_type* vs) {
    batch_inlined<P>(view, first, n, r, ts, us, vs);
}

}  // namespace detail

/// The scalar path: one record against a ray prepared in the record's frame; sets `hit`
/// only on a hit.
template <TriangleIntersector P>
[[gnu::always_inline]] inline bool intersect_record(const P& p, const RayDataOf<P>& r,
                                                    TriangleHit<typename P::scalar_type>& hit) {
    using T = typename P::scalar_type;
    constexpr int F = field_count<P>;
    T t, u, v;
    bool ok;
    if constexpr (requires(const T* const (&in)[F], const T* (&out)[F]) { P::select_fields(in, r, out); }) {
        const auto x = detail::fields_of(p);
        const T* in[F];
        const T* f[F];
        for (int k = 0; k < F; ++k) in[k] = x.data() + k;
        P::select_fields(in, r, f);
        ok = detail::gather<P>(f, 0).test(r, t, u, v);
    } else {
        ok = p.test(r, t, u, v);
    }
    if (ok) hit = {t, u, v};
    return ok;
}

}  // namespace glint
