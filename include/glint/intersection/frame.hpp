// glint/intersection/frame.hpp: where a triangle record's coordinates live, and how a ray
// gets there.
//
// Records are built from vertices relative to a frame origin, and a ray is translated into
// that frame before the test. A policy names its frame with `using frame = ...`; without
// one it gets the IdentityFrame: world coordinates, every step of which is the identity and
// compiles away. The IVM test needs OffsetFrames (Szécsi 2009, §4.1 assumes that no
// triangle plane passes through the origin, see ivm.hpp): every group of records gets an
// origin away from its planes.
//
// The containers (Triangle, TriangleStore, TriangleLeaves, BruteForce) always call the
// frame: choose() when they build, local() when they query, and for tree leaves leaf(),
// test_leaf() and records(), which decide what a leaf reference (first, count) counts and
// how it is tested: padded records in the identity frame (no indirection), groups of records
// sharing an origin with offset frames.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <span>
#include <utility>

#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/intersector.hpp>

namespace glint {

namespace detail {

/// How well a frame origin suits the IVM of triangle (a, b, c) given relative to world:
/// the distance of the origin from the triangle's plane divided by (distance to the
/// triangle + triangle size). The IVM's rounding error in barycentrics grows as 1 /
/// quality; 0 means the plane passes through the frame origin. Degenerate triangles (which
/// never hit) get +inf so they do not constrain the choice.
inline double frame_quality(const Vec3d& origin, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
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
/// frame's coordinates (tests/test_intersection.cpp measures it).
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

/// `x` rounded to T component by component, as a double. Each rounding goes through a
/// volatile T: GCC 12 (-O2 and above) vectorizes `Vec3d(Vec3<float>(x))` into code that keeps
/// two components unrounded (measured: OffsetFrames::choose returned -0x1.c5b048fb1c56ep-1
/// for -0x1.c5b048p-1), so records were built in a frame a few ulps away from the rounded
/// origin that rays are translated by, and the same triangle's record depended on where the
/// compiler inlined the store's builder (the ray-tile engine and brute force disagreed in the
/// last bits of some hits; tests/test_intersection.cpp and tests/test_cones.cpp check it).
template <class T>
Vec3d rounded_to(const Vec3d& x) {
    Vec3d out;
    for (int k = 0; k < 3; ++k) {
        const volatile T r = static_cast<T>(x[k]);
        out[k] = static_cast<double>(r);
    }
    return out;
}

/// Record slots of `n` records padded to whole batches.
template <std::unsigned_integral U>
constexpr U padded(U n) {
    constexpr U w = U(batch_width);
    return (n + w - 1) / w * w;
}

}  // namespace detail

/// World coordinates: the origin is 0 for every triangle, a ray is used as it is, and a tree
/// leaf is a run of padded records, tested with the ray prepared once per query.
struct IdentityFrame {
    /// The world origin (0, 0, 0) for any triangles; `quality` is set to +inf (no constraint).
    template <class T>
    static Vec3d choose(std::span<const TriangleVertices<T>>, double& quality) {
        quality = infinity<double>;
        return Vec3d(0.0);
    }
    /// Whether TriangleStore::add_each appends a triangle to the previous one's group: always,
    /// as every record shares the one world frame.
    template <class T>
    static bool joins(const Vec3<T>&, const Vec3<T>&) {
        return true;
    }
    /// `ray` itself, unchanged (no copy): world coordinates are the frame's.
    template <class T>
    static const Ray<T>& local(const Ray<T>& ray, const Vec3<T>&) {
        return ray;
    }
    /// The leaf reference of a padded block: its records, padding included.
    template <class Store>
    static std::pair<std::uint32_t, std::uint32_t> leaf(const Store& s, typename Store::BlockRef ref) {
        const auto& g = s.group(ref.group_begin);  // one group in the world frame
        return {g.begin, detail::padded(g.end - g.begin)};
    }
    /// Tests leaf (first, count) of store `s`, a run of padded records, with `world`, the ray
    /// data prepared once per query. Left to the compiler to inline or not.
    template <bool Any, class P, class Store, class Hit>
    static bool test_leaf(const Store& s, std::uint32_t first, std::uint32_t count, const Ray<typename Store::T>&,
                          const RayDataOf<P>& world, Hit& hit) {
        return s.template test_batches<Any>(first, first + count, world, hit);
    }
    /// Records leaf (first, count) tests: `count`, which already counts padded records.
    template <class Store>
    static std::uint64_t records(const Store&, std::uint32_t, std::uint32_t count) {
        return count;
    }
};

/// A frame per group of records, with its origin away from the group's triangle planes
/// (detail::choose_frame; blocks are split until each group reaches
/// detail::min_frame_quality); a tree leaf is a run of groups, and the ray is translated
/// and prepared once per group.
struct OffsetFrames {
    /// Origin for a group of triangles (detail::choose_frame), rounded to T; `quality` gets
    /// its quality (detail::frame_quality), which the store compares with min_frame_quality.
    template <class T>
    static Vec3d choose(std::span<const TriangleVertices<T>> tris, double& quality) {
        // Rounded to T: the origin exactly as rays will be translated by it.
        return detail::rounded_to<T>(detail::choose_frame<T>(tris, quality));
    }
    /// TriangleStore::add_each gives every triangle a group of its own, even where two
    /// neighbours chose the same origin: the reference that the trees and the ray-tile engine
    /// are compared with bit for bit tests each record alone, in its own frame.
    template <class T>
    static bool joins(const Vec3<T>&, const Vec3<T>&) {
        return false;
    }
    /// A copy of `ray` translated into the frame at `origin` (direction and interval kept).
    template <class T>
    static Ray<T> local(const Ray<T>& ray, const Vec3<T>& origin) {
        Ray<T> r = ray;
        r.origin -= origin;
        return r;
    }
    /// The leaf reference of a block: its groups (first group, group count).
    template <class Store>
    static std::pair<std::uint32_t, std::uint32_t> leaf(const Store&, typename Store::BlockRef ref) {
        return {ref.group_begin, ref.group_end - ref.group_begin};
    }
    /// Tests leaf (first, count) of store `s`, a run of groups, each with the ray translated
    /// into the group's frame and prepared with the interval (ray.tmin, min(ray.tmax, hit.t)).
    /// Always inlined into the tree's traversal: called out of line it was slower on primary
    /// rays (docs/history/trees.md, "Leaf tests after the frames change").
    template <bool Any, class P, class Store, class Hit>
    [[gnu::always_inline]] static bool test_leaf(const Store& s, std::uint32_t first, std::uint32_t count,
                                                 const Ray<typename Store::T>& ray, const RayDataOf<P>&, Hit& hit) {
        bool found = false;
        for (const std::uint32_t end = first + count; first < end; ++first) {
            const auto& g = s.group(first);
            Ray<typename Store::T> r = local(ray, g.origin);
            r.tmax = tmax_before(ray, hit);
            if (s.template test_batches<Any>(g.begin, g.end, P::prepare(r), hit)) {
                if constexpr (Any) return true;
                found = true;
            }
        }
        return found;
    }
    /// Records leaf (first, count) tests: the padded records of its `count` groups (O(count)).
    template <class Store>
    static std::uint64_t records(const Store& s, std::uint32_t first, std::uint32_t count) {
        std::uint64_t n = 0;
        for (std::uint32_t g = first; g < first + count; ++g) n += detail::padded(s.group(g).end - s.group(g).begin);
        return n;
    }
};

namespace detail {
template <class P>
struct FrameOf {
    using type = IdentityFrame;
};
template <class P>
    requires requires { typename P::frame; }
struct FrameOf<P> {
    using type = typename P::frame;
};
}  // namespace detail

/// The frame of policy P: P::frame, or the IdentityFrame.
template <class P>
using FrameOf = typename detail::FrameOf<P>::type;

}  // namespace glint
