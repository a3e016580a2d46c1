// glint/cones/ray_tiles.hpp: the hierarchical ray engine on the CPU: a hierarchy over rays
// (tiles of an image, one enclosing cone each) instead of over objects.
//
// Szécsi 2009, ch. 6. The ray engine tests every ray against
// every triangle. Section 6.1 splits the ray array into tiles and, for
// every triangle and tile, first tests the triangle's enclosing sphere against the tile's
// enclosing cone; only tiles that pass run the ray-triangle tests. Section 6.3
// iterates passes for multiple refractions and reflections: in every
// pass the cones are rebuilt for the new generation of rays, and rays whose path has
// terminated (no hit, or the shader ends it) drop out (Szécsi 2009, §6.4 uses the stencil buffer
// for this; here an active flag per ray). Per Szécsi 2009, §6.3.1 the triangle record
// is the IVM (any TriangleIntersector policy works) plus its bounding sphere (sphere.hpp).
//
// CPU form of the GPU passes: the loop is tile-major (for every tile: its cone, then every
// triangle's sphere against it, then the tile's active rays against each triangle that
// passes), so a tile's rays stay in cache. Within a ray, triangles are tested in index order
// with the same records, frames and kernel as BruteForce<P> (one store block per
// triangle), and a triangle is culled only when it cannot be hit (the cone holds every
// point of every ray of the tile, the sphere every point of the triangle, and the test is
// conservative), so every hit is bit-for-bit the brute-force hit (tests/test_cones.cpp).
//
// Hot paths do not allocate: per-frame buffers live in a TileWorkspace the caller keeps.
#pragma once

#include <algorithm>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numeric>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/cones/cone.hpp>
#include <glint/cones/sphere.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// A width x height array of rays (row-major, ray (x, y) at index y * width + x) split into
/// square tiles of `tile` x `tile` rays (the last row and column of tiles may be partial).
/// Szécsi 2009, §6.4 uses 256 x 256 rays in 16 x 16 tiles.
struct TileGrid {
    /// \var height
    /// Rays per column of the array (0 in a default-constructed grid).

    /// Rays per row of the array (0 in a default-constructed grid).
    int width = 0, height = 0, tile = 16;  ///< Side of a square tile, in rays (Szécsi 2009, §6.4: 16).

    TileGrid() = default;
    /// A w x h ray array in tiles of t x t rays. Throws Error unless w, h, t > 0 and w h < 2^32.
    TileGrid(int w, int h, int t = 16) : width(w), height(h), tile(t) {
        if (w <= 0 || h <= 0 || t <= 0 || std::int64_t(w) * h > std::int64_t(std::numeric_limits<std::uint32_t>::max()))
            throw Error("TileGrid: need width, height, tile > 0 and at most 2^32 rays, got " + std::to_string(w) + " x " +
                        std::to_string(h) + " rays in tiles of " + std::to_string(t));
    }
    /// Tiles per row, ceil(width / tile).
    int tiles_x() const { return (width + tile - 1) / tile; }
    /// Tiles per column, ceil(height / tile).
    int tiles_y() const { return (height + tile - 1) / tile; }
    /// Number of tiles, tiles_x() * tiles_y().
    std::size_t tile_count() const { return std::size_t(tiles_x()) * std::size_t(tiles_y()); }
    /// Number of rays, width * height.
    std::size_t ray_count() const { return std::size_t(width) * std::size_t(height); }
};

/// Options of the ray-tile engine.
///
/// Szécsi's hierarchy (Szécsi 2009, ch. 6) has two levels (rays and tiles). Adaptive split
/// is an extension in the direction of Szécsi 2009, §6.7 (multi-level ray hierarchies of
/// Roger et al.): a tile of m rays whose cone passes P of the N triangles' spheres is split into
/// quadrants (recursively, down to `min_tile` rays on a side) when the tests a split may
/// save exceed its cost, all in units of one ray-triangle test:
///     split_gain * P * m  >  4 * sphere_cost * N  +  cone_cost * m
/// (four sub-cones each test N spheres; each ray enters cone construction again). The
/// defaults were set on bench_cones (sphere and knot scenes). With `min_tile` at least the
/// grid's tile size (TileOptions::fixed()) it is Szécsi's scheme.
struct TileOptions {
    ConeOptions cone;  ///< How each tile's enclosing cone is built.
    int min_tile = 4;  ///< Smallest side, in rays, a tile is split down to (>= 1; int max: no split).
    double split_gain = 0.3;    ///< expected fraction of a tile's tests that a split saves
    double sphere_cost = 0.5;   ///< cost of one cone-sphere test, in ray-triangle tests
    double cone_cost = 10.0;    ///< one ray's share of building a cone, in ray-triangle tests

    /// Szécsi's fixed tiles: no split.
    static TileOptions fixed() {
        TileOptions o;
        o.min_tile = std::numeric_limits<int>::max();
        return o;
    }
    /// Throws Error for invalid cone options, min_tile < 1 or a negative (or NaN) cost or gain.
    void validate() const {
        cone.validate();
        if (min_tile < 1) throw Error("TileOptions::min_tile must be >= 1, got " + std::to_string(min_tile));
        if (!(split_gain >= 0.0 && sphere_cost >= 0.0 && cone_cost >= 0.0))
            throw Error("TileOptions: split_gain, sphere_cost and cone_cost must be >= 0");
    }
};

/// Counts of one or more passes.
struct PassStats {
    int passes = 0;                  ///< passes run
    std::uint64_t rays = 0;          ///< ray segments traced (active rays summed over passes)
    std::uint64_t hits = 0;          ///< of which hit a triangle
    std::uint64_t tests = 0;         ///< ray-triangle tests (0 where the accelerator cannot count)
    std::uint64_t sphere_tests = 0;  ///< cone-sphere tests
    std::uint64_t tiles = 0;         ///< tiles with active rays (one cone each)
    std::uint64_t tiles_all = 0;     ///< of which got the cone that admits every ray

    /// Ray-triangle tests per traced ray segment (0 when no ray was traced).
    double tests_per_ray() const { return rays ? double(tests) / double(rays) : 0.0; }
    /// Adds every count of `o` (statistics of further passes or frames).
    PassStats& operator+=(const PassStats& o) {
        passes += o.passes;
        rays += o.rays;
        hits += o.hits;
        tests += o.tests;
        sphere_tests += o.sphere_tests;
        tiles += o.tiles;
        tiles_all += o.tiles_all;
        return *this;
    }
};

/// Per-frame buffers, kept by the caller and reused (they grow once, then never allocate).
template <Scalar T>
struct TileWorkspace {
    std::vector<std::uint8_t> active;    ///< per ray: still on its path
    std::vector<StoreHit<T>> hits;       ///< per ray: the closest hit of the last pass
    std::vector<Cone<T>> cones;          ///< per tile: the cone of the last pass
    std::vector<std::uint32_t> index;    ///< one tile's active rays
    std::vector<std::uint8_t> pass;      ///< one chunk of cone-sphere results
};

/// A shader for trace_passes: `shade(i, ray, hit, found)` is called after every pass for
/// every active ray i (rays that cannot hit anything are never active); it may replace `ray` with the next segment of the path and returns
/// whether the path goes on (a ray without a hit normally ends: Szécsi 2009, §6.4).
template <class S, class T>
concept PassShader = requires(S s, std::size_t i, Ray<T>& r, const StoreHit<T>& h, bool f) {
    { s(i, r, h, f) } -> std::convertible_to<bool>;
};

namespace detail {

/// The pass loop shared by the engine and by per-ray accelerators: `find_hits(rays,
/// active, hits)` fills hits for the active rays and returns the pass's counts.
template <class T, class Find, class Shade>
PassStats run_passes(std::span<Ray<T>> rays, int max_passes, TileWorkspace<T>& ws, Find&& find_hits,
                     Shade&& shade) {
    if (max_passes < 0) throw Error("trace_passes: max_passes must be >= 0, got " + std::to_string(max_passes));
    // Rays that cannot hit anything (ray_can_hit: NaN, infinite or zero) are inactive from
    // the start, like pixels where no refractive surface is visible (Szécsi 2009, §6.4).
    ws.active.resize(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) ws.active[i] = ray_can_hit(rays[i]) ? 1 : 0;
    ws.hits.resize(rays.size());
    PassStats total;
    for (int pass = 0; pass < max_passes; ++pass) {
        std::uint64_t live = 0;
        for (std::uint8_t a : ws.active) live += a;
        if (live == 0) break;
        PassStats s = find_hits(std::span<const Ray<T>>(rays), std::span<const std::uint8_t>(ws.active),
                                std::span<StoreHit<T>>(ws.hits));
        s.passes = 1;
        s.rays = live;
        for (std::size_t i = 0; i < rays.size(); ++i) {
            if (!ws.active[i]) continue;
            const bool found = ws.hits[i].id != std::numeric_limits<std::uint32_t>::max();
            s.hits += found;
            ws.active[i] = shade(i, rays[i], std::as_const(ws.hits[i]), found) ? 1 : 0;
        }
        total += s;
    }
    return total;
}

}  // namespace detail

/// The hierarchical ray engine over triangles with intersector P (Szécsi 2009, ch. 6).
template <TriangleIntersector P>
class RayTileEngine {
public:
    using scalar_type = typename P::scalar_type;  ///< Scalar type of the intersector (float or double).
    using T = scalar_type;                         ///< Short name for scalar_type.
    /// Triangles whose spheres are tested against a cone at once (branch-free, vectorized).
    static constexpr std::size_t chunk = 64;

    /// Stores `tris` as P's records (one block per triangle, as BruteForce<P>) and their bounding
    /// spheres. Throws Error for invalid `opt` or 2^32 - 1 triangles or more. Allocates.
    explicit RayTileEngine(std::span<const TriangleVertices<T>> tris, const TileOptions& opt = {}) : opt_(opt) {
        opt_.validate();
        if (tris.size() >= std::numeric_limits<std::uint32_t>::max())
            throw Error("RayTileEngine: at most 2^32 - 2 triangles, got " + std::to_string(tris.size()));
        const std::size_t n = tris.size();
        refs_.reserve(n);
        cx_.resize(n);
        cy_.resize(n);
        cz_.resize(n);
        cr_.resize(n);
        constexpr T eps = std::numeric_limits<T>::epsilon();
        for (std::size_t i = 0; i < n; ++i) {
            // One block per triangle, exactly as BruteForce<P> stores them, so that the
            // records, frames and therefore the hits are the same.
            const std::uint32_t id = static_cast<std::uint32_t>(i);
            refs_.push_back(store_.add_block(tris.subspan(i, 1), std::span(&id, 1)));
            const BoundingSphere<T> s = min_enclosing_sphere(tris[i]);
            cx_[i] = s.center.x;
            cy_[i] = s.center.y;
            cz_[i] = s.center.z;
            // The part of cone_test_radius that depends on the triangle only.
            cr_[i] = s.radius >= T(0) ? s.radius + T(16) * eps * glm::length(s.center) : -infinity<T>;
        }
    }

    /// Number of triangles; hit ids are their indices in the span given.
    std::size_t triangle_count() const { return refs_.size(); }
    /// The intersector's triangle records.
    const TriangleStore<P>& store() const { return store_; }
    /// The options given at construction.
    const TileOptions& options() const { return opt_; }

    /// One pass: for every ray i with active[i] != 0, hits[i] becomes its closest hit (id =
    /// max when none); other entries are left alone. ws.cones holds the cones of the tiles
    /// (and sub-tiles) that were tested.
    PassStats trace(std::span<const Ray<T>> rays, std::span<const std::uint8_t> active, const TileGrid& grid,
                    std::span<StoreHit<T>> hits, TileWorkspace<T>& ws) const {
        if (rays.size() != grid.ray_count() || active.size() != rays.size() || hits.size() != rays.size())
            throw Error("RayTileEngine::trace: the grid has " + std::to_string(grid.ray_count()) + " rays but got " +
                        std::to_string(rays.size()) + " rays, " + std::to_string(active.size()) + " flags, " +
                        std::to_string(hits.size()) + " hits");
        ws.cones.clear();
        ws.index.resize(std::size_t(grid.tile) * grid.tile);
        ws.pass.resize(refs_.size());
        for (std::size_t i = 0; i < rays.size(); ++i)
            if (active[i]) hits[i] = StoreHit<T>{};
        PassStats s;
        const Pass pass{rays, active, hits, grid, store_.view()};
        for (int ty = 0; ty < grid.tiles_y(); ++ty)
            for (int tx = 0; tx < grid.tiles_x(); ++tx)
                trace_tile(pass, tx * grid.tile, ty * grid.tile, std::min(grid.width, (tx + 1) * grid.tile),
                           std::min(grid.height, (ty + 1) * grid.tile), ws, s);
        return s;
    }

    /// Up to max_passes passes of trace + shade (Szécsi 2009, §6.3): the rays are replaced in
    /// place by the shader; paths it ends drop out of later passes.
    template <class Shade>
        requires PassShader<Shade, T>
    PassStats trace_passes(std::span<Ray<T>> rays, const TileGrid& grid, int max_passes, Shade&& shade,
                           TileWorkspace<T>& ws) const {
        return detail::run_passes<T>(
            rays, max_passes, ws,
            [&](std::span<const Ray<T>> r, std::span<const std::uint8_t> a, std::span<StoreHit<T>> h) {
                return trace(r, a, grid, h, ws);
            },
            shade);
    }

private:
    struct Pass {
        std::span<const Ray<T>> rays;
        std::span<const std::uint8_t> active;
        std::span<StoreHit<T>> hits;
        const TileGrid& grid;
        RecordView<P> view;
    };

    /// The rays of the rectangle [x0, x1) x [y0, y1): their cone, then every triangle's
    /// sphere against it, then the rays against the triangles that pass, unless the cost
    /// model of TileOptions splits the rectangle into quadrants (down to min_tile).
    void trace_tile(const Pass& p, int x0, int y0, int x1, int y1, TileWorkspace<T>& ws, PassStats& s) const {
        std::size_t m = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const std::size_t i = std::size_t(y) * p.grid.width + x;
                if (p.active[i] && ray_can_hit(p.rays[i])) ws.index[m++] = static_cast<std::uint32_t>(i);
            }
        if (m == 0) return;
        const std::span<const std::uint32_t> idx(ws.index.data(), m);
        const Cone<T> cone = detail::enclosing_cone_of<T>(
            m, [&](std::size_t k) -> const Ray<T>& { return p.rays[idx[k]]; }, opt_.cone);
        const std::size_t n = refs_.size();
        s.sphere_tests += n;
        // Every triangle's sphere against the cone, into ws.pass.
        constexpr T eps = std::numeric_limits<T>::epsilon();
        const T tile_r = cone.slack + T(16) * eps * glm::length(cone.apex);
        std::uint8_t* pass = ws.pass.data();
        std::size_t passed = n;
        if (cone.all) {
            std::fill(pass, pass + n, std::uint8_t(1));
        } else {
            passed = 0;
            for (std::size_t first = 0; first < n; first += chunk) {
                const std::size_t cnt = std::min(chunk, n - first);
                sphere_chunk(cone, tile_r, first, cnt, pass + first);
                for (std::size_t j = 0; j < cnt; ++j) passed += pass[first + j];
            }
        }
        // Split when the tests it may save outweigh its cost (TileOptions).
        const bool can_split = x1 - x0 > opt_.min_tile || y1 - y0 > opt_.min_tile;
        if (can_split && opt_.split_gain * double(passed) * double(m) >
                             4.0 * opt_.sphere_cost * double(n) + opt_.cone_cost * double(m)) {
            const int xm = x1 - x0 > opt_.min_tile ? x0 + (x1 - x0 + 1) / 2 : x1;
            const int ym = y1 - y0 > opt_.min_tile ? y0 + (y1 - y0 + 1) / 2 : y1;
            trace_tile(p, x0, y0, xm, ym, ws, s);
            if (xm < x1) trace_tile(p, xm, y0, x1, ym, ws, s);
            if (ym < y1) trace_tile(p, x0, ym, xm, y1, ws, s);
            if (xm < x1 && ym < y1) trace_tile(p, xm, ym, x1, y1, ws, s);
            return;
        }
        ws.cones.push_back(cone);
        ++s.tiles;
        s.tiles_all += cone.all;
        // (A split returned above: the sub-tiles reuse ws.index and ws.pass.)
        for (std::size_t j = 0; j < n; ++j) {
            if (!pass[j]) continue;
            test_rays(p.view, refs_[j], p.rays, idx, p.hits);
            s.tests += m;
        }
    }

    /// The rays idx against one triangle's block: exactly TriangleStore::closest_hit on a
    /// one-record block (the same translation into the record's frame, the same batch
    /// kernel with n = 1, the same strict "closer than the best so far" update), without
    /// rebuilding the view for every ray.
    static void test_ray(const RecordView<P>& view, const typename TriangleStore<P>::Group& g,
                         std::uint32_t id, const Ray<T>& ray, StoreHit<T>& hit) {
        Ray<T> local = ray;
        local.tmax = std::min(ray.tmax, hit.t);
        local.origin = ray.origin - g.origin;
        const auto rd = P::prepare(local);
        T t, u, v;
        detail::batch<P>(view, g.begin, 1, rd, &t, &u, &v);
        if (t < local.tmax) {
            hit.t = t;
            hit.u = u;
            hit.v = v;
            hit.id = id;
        }
    }

    void test_rays(const RecordView<P>& view, typename TriangleStore<P>::BlockRef ref,
                   std::span<const Ray<T>> rays, std::span<const std::uint32_t> idx, std::span<StoreHit<T>> hits) const {
        for (std::uint32_t gi = ref.group_begin; gi < ref.group_end; ++gi) {
            const auto& g = store_.group(gi);
            if (g.end - g.begin == 1) {
                const std::uint32_t id = store_.id(g.begin);
                for (std::uint32_t k : idx) test_ray(view, g, id, rays[k], hits[k]);
            } else {
                for (std::uint32_t k : idx) store_.closest_hit({gi, gi + 1}, rays[k], hits[k]);
            }
        }
    }

    /// Cone-sphere test (sphere.hpp, cone_meets_sphere) for triangles first .. first+cnt-1,
    /// written over the structure-of-arrays spheres without branches so that it vectorizes.
    void sphere_chunk(const Cone<T>& cone, T tile_r, std::size_t first, std::size_t cnt, std::uint8_t* pass) const {
        constexpr T eps = std::numeric_limits<T>::epsilon();
        const T ax = cone.apex.x, ay = cone.apex.y, az = cone.apex.z;
        const T xx = cone.axis.x, xy = cone.axis.y, xz = cone.axis.z;
        const T cs = cone.cos_half, sn = cone.sin_half;
        const T *px = cx_.data() + first, *py = cy_.data() + first, *pz = cz_.data() + first, *pr = cr_.data() + first;
        for (std::size_t j = 0; j < cnt; ++j) {
            const T wx = px[j] - ax, wy = py[j] - ay, wz = pz[j] - az;
            const T h = wx * xx + wy * xy + wz * xz;
            const T kx = wy * xz - wz * xy, ky = wz * xx - wx * xz, kz = wx * xy - wy * xx;
            const T rho = std::sqrt(kx * kx + ky * ky + kz * kz);
            const T r = pr[j] + tile_r + T(16) * eps * (rho + std::abs(h));
            const bool side = rho * sn + h * cs >= T(0);
            const bool near_generator = rho * cs - h * sn <= r;
            const bool near_apex = r >= T(0) && h * h + rho * rho <= r * r;  // r = -inf: empty sphere
            pass[j] = static_cast<std::uint8_t>(side ? near_generator : near_apex);
        }
    }

    TileOptions opt_;
    TriangleStore<P> store_;
    std::vector<typename TriangleStore<P>::BlockRef> refs_;
    std::vector<T> cx_, cy_, cz_, cr_;  // sphere centres and radii (with the triangle's rounding margin)
};

/// The same passes with a per-ray accelerator (BruteForce, a KdTree: any RayAccelerator),
/// the reference the engine is compared with. PassStats::tests is left 0 (per-ray
/// accelerators do not count their tests).
template <RayAccelerator A, class Shade>
    requires PassShader<Shade, typename A::scalar_type>
PassStats trace_passes(const A& accel, std::span<Ray<typename A::scalar_type>> rays, int max_passes, Shade&& shade,
                       TileWorkspace<typename A::scalar_type>& ws) {
    using T = typename A::scalar_type;
    return detail::run_passes<T>(
        rays, max_passes, ws,
        [&](std::span<const Ray<T>> r, std::span<const std::uint8_t> a, std::span<StoreHit<T>> h) {
            for (std::size_t i = 0; i < r.size(); ++i) {
                if (!a[i]) continue;
                h[i] = StoreHit<T>{};
                accel.closest_hit(r[i], h[i]);
            }
            return PassStats{};
        },
        shade);
}

}  // namespace glint
