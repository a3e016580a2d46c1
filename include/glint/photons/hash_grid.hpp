// glint/photons/hash_grid.hpp: a hashed uniform grid over spheres (a visible point and its
// gather radius), for stochastic progressive photon mapping's photon pass (Hachisuka and
// Jensen 2009, §4.3: the hit points are stored in a hashed grid, and each photon looks up the
// points whose sphere holds it). The cell size is the largest radius; each sphere is listed
// once in every bucket of the cells its bounding box overlaps, cells hashed (Teschner et al. 2003's primes) into
// a table of at least twice as many buckets as listings. Buckets are stored flat (counts,
// prefix sums, then indices in the spheres' order), so a build is deterministic and a query
// allocates nothing. Hash collisions only cost distance tests: a query checks every listed
// sphere's own radius.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <glint/core/buckets.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>

namespace glint {

/// A hashed uniform grid over spheres for point-in-sphere queries (Hachisuka and Jensen 2009,
/// §4.3); it copies the spheres, is immutable once built and safe to query from many threads.
template <Scalar T>
class SphereHashGrid {
public:
    SphereHashGrid() = default;

    /// The grid over spheres (centres[i], radii[i]); a sphere of radius <= 0 is left out.
    SphereHashGrid(std::span<const Vec3<T>> centres, std::span<const T> radii) {
        if (centres.size() != radii.size()) throw Error("SphereHashGrid: centres and radii differ in count");
        centres_.assign(centres.begin(), centres.end());
        r2_.reserve(radii.size());
        T rmax = T(0);
        for (const T r : radii) {
            r2_.push_back(r > T(0) ? r * r : T(-1));
            rmax = std::max(rmax, r);
        }
        if (!(rmax > T(0))) return;
        cell_ = rmax;
        std::size_t cells = 0;  // with the full hash: one listing per overlapped cell
        mask_ = ~std::uint64_t(0);
        for_each_listing([&](std::size_t, std::uint64_t) { ++cells; });
        std::size_t buckets = 1;
        while (buckets < 2 * cells) buckets <<= 1;
        mask_ = buckets - 1;
        fill_buckets(buckets, [&](auto emit) { for_each_listing([&](std::size_t i, std::uint64_t h) { emit(i, h); }); }, start_,
                     index_);
    }

    /// Calls visit(i, d2) for every sphere i that holds point p (d2: squared distance to its
    /// centre, below its squared radius), each once.
    template <class Visit>
    void query(const Vec3<T>& p, Visit&& visit) const {
        if (index_.empty()) return;
        const std::uint64_t h = hash(cell_of(p));
        for (std::uint32_t k = start_[h]; k < start_[h + 1]; ++k) {
            const std::uint32_t i = index_[k];
            const Vec3<T> d = p - centres_[i];
            const T d2 = glm::dot(d, d);
            if (d2 < r2_[i]) visit(std::size_t(i), d2);
        }
    }

    /// Number of (sphere, bucket) listings stored: the grid's size.
    std::size_t listings() const { return index_.size(); }
    /// Edge of a grid cell: the largest radius (0 when no sphere has a positive radius).
    T cell_size() const { return cell_; }

private:
    glm::vec<3, std::int64_t> cell_of(const Vec3<T>& p) const {
        return glm::vec<3, std::int64_t>(std::int64_t(std::floor(p.x / cell_)), std::int64_t(std::floor(p.y / cell_)),
                                         std::int64_t(std::floor(p.z / cell_)));
    }
    /// The bucket of cell c (the full hash while the table is being sized).
    std::uint64_t hash(const glm::vec<3, std::int64_t>& c) const {
        const std::uint64_t h = (std::uint64_t(c.x) * 73856093u) ^ (std::uint64_t(c.y) * 19349663u) ^ (std::uint64_t(c.z) * 83492791u);
        return h & mask_;
    }
    /// f(sphere, bucket) for every cell each sphere's bounding box overlaps.
    template <class F>
    void for_each_listing(F&& f) const {
        for (std::size_t i = 0; i < centres_.size(); ++i) {
            if (!(r2_[i] > T(0))) continue;
            const T r = std::sqrt(r2_[i]);
            const auto lo = cell_of(centres_[i] - Vec3<T>(r)), hi = cell_of(centres_[i] + Vec3<T>(r));
            // At most 3 cells per axis (2 r <= twice the cell size), 4 where rounding in cell_of
            // adds one; a bucket two of them hash to is listed once, so that a query visits each
            // sphere once.
            std::uint64_t seen[64];
            int count = 0;
            for (std::int64_t z = lo.z; z <= hi.z; ++z)
                for (std::int64_t y = lo.y; y <= hi.y; ++y)
                    for (std::int64_t x = lo.x; x <= hi.x; ++x) {
                        const std::uint64_t h = hash({x, y, z});
                        if (std::find(seen, seen + count, h) != seen + count) continue;
                        seen[count++] = h;
                        f(i, h);
                    }
        }
    }

    std::vector<Vec3<T>> centres_;
    std::vector<T> r2_;
    T cell_ = T(0);
    std::uint64_t mask_ = 0;
    std::vector<std::uint32_t> start_, index_;
};

}  // namespace glint
