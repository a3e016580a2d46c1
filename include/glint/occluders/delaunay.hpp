// glint/occluders/delaunay.hpp: 3D Delaunay tetrahedralization by Bowyer-Watson.
//
// Szécsi 2009, §5.2: "A Delaunay mesh is a decomposition of space into
// tetrahedra, the circumspheres of which cannot contain any node of the mesh. Using the
// Bowyer-Watson algorithm [Bow81, Wat81] ... an incremental algorithm, starting off from an
// initial enclosing tessellation, adding points sequentially."
//
// Implementation:
// - The initial tessellation is one tetrahedron whose vertices lie 1e4 bounding radii from
//   the points' centre; its four vertices are indices 0..3 (super vertices). Tetrahedra that
//   use them are not reported by tetrahedra() (Delaunay tetrahedra of the hull whose
//   circumspheres reach the super vertices may be missing; Szécsi 2009 discards outer tetrahedra
//   anyway, section 5.2.1).
// - Points are inserted in a spatially coherent order (Morton order of a 2^10 grid, shuffled
//   in rounds as in a biased randomized insertion order), and located by a remembering
//   stochastic visibility walk from the last created tetrahedron, with exact orient3d.
// - The cavity is the connected set of tetrahedra whose circumsphere contains the new point
//   *strictly* (exact insphere > 0). With exact predicates this makes degenerate input safe:
//   a point on a face or edge is strictly inside the circumsphere of every tetrahedron that
//   contains it, and a point on the circumsphere of a tetrahedron T adjacent to the cavity
//   cannot lie in the plane of the face they share (in that plane the two circumspheres cut
//   the same disk), so every new tetrahedron has strictly positive orientation; cospherical
//   and gridded inputs simply give one of their Delaunay tetrahedralizations.
// - Duplicate points (equal coordinates) are skipped and reported by duplicate_count().
// Every tetrahedron is stored positively oriented (orient3d(v0, v1, v2, v3) > 0); face i is
// the one opposite vertex i and neighbour[i] the tetrahedron across it (-1: none).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/occluders/predicates.hpp>

namespace glint {

/// One tetrahedron of the mesh, positively oriented (orient3d(v0, v1, v2, v3) > 0).
struct Tetrahedron {
    std::array<std::int32_t, 4> v{};          ///< Vertex indices into Delaunay::points().
    std::array<std::int32_t, 4> neighbour{};  ///< Across the face opposite v[i]; -1 none.
};

/// 3D Delaunay tetrahedralization of points in precision T (Bowyer-Watson with exact
/// predicates; see the file comment).
template <Scalar T>
class Delaunay {
public:
    static constexpr int super_vertices = 4;  ///< Enclosing vertices, indices 0 ... 3 of points().

    Delaunay() = default;

    /// Tetrahedralizes `pts` (finite coordinates; throws glint::Error otherwise).
    explicit Delaunay(std::span<const Vec3<T>> pts, std::uint64_t seed = 1) { build(pts, seed); }

    /// Replaces the mesh with the tetrahedralization of `pts`; `seed` drives the randomized
    /// insertion order. Throws glint::Error for non-finite coordinates or 2^28 points or more.
    void build(std::span<const Vec3<T>> pts, std::uint64_t seed = 1) {
        tets_.clear();
        alive_.clear();
        free_.clear();
        points_.clear();
        duplicates_ = 0;
        if (pts.size() > std::size_t(INT32_MAX / 8))
            throw Error("glint::Delaunay: " + std::to_string(pts.size()) + " points exceed the index range");
        Vec3d lo(infinity<double>), hi(-infinity<double>);
        for (std::size_t i = 0; i < pts.size(); ++i) {
            if (!all_finite(pts[i]))
                throw Error("glint::Delaunay: point " + std::to_string(i) + " is not finite");
            lo = glm::min(lo, Vec3d(pts[i]));
            hi = glm::max(hi, Vec3d(pts[i]));
        }
        check_range(pts);
        if (pts.empty()) lo = hi = Vec3d(0);
        const Vec3d c = 0.5 * (lo + hi);
        const double r = std::max(0.5 * glm::length(hi - lo), 1e-30 + 1e-12 * glm::length(c));
        const double s = 1e4 * r;
        // A regular-ish tetrahedron around c containing the ball of radius s / 3.
        points_.push_back(c + s * Vec3d(1, 1, 1));
        points_.push_back(c + s * Vec3d(1, -1, -1));
        points_.push_back(c + s * Vec3d(-1, 1, -1));
        points_.push_back(c + s * Vec3d(-1, -1, 1));
        Tetrahedron root;
        root.v = {0, 1, 2, 3};
        root.neighbour = {-1, -1, -1, -1};
        if (orient3d(points_[0], points_[1], points_[2], points_[3]) < 0) std::swap(root.v[0], root.v[1]);
        tets_.push_back(root);
        alive_.push_back(1);
        for (const auto& p : pts) points_.push_back(Vec3d(p));

        // Insertion order: Morton codes on a 2^10 grid, then BRIO-like rounds.
        std::vector<std::pair<std::uint32_t, std::int32_t>> order(pts.size());
        const Vec3d ext = glm::max(hi - lo, Vec3d(1e-300));
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const Vec3d q = (Vec3d(pts[i]) - lo) / ext * 1023.0;
            order[i] = {morton(std::uint32_t(q.x), std::uint32_t(q.y), std::uint32_t(q.z)),
                        std::int32_t(i + super_vertices)};
        }
        Pcg32 rng(seed);
        // Random rounds of doubling size, each sorted along the curve.
        for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng.bounded(std::uint32_t(i))]);
        std::size_t begin = 0, round = std::min<std::size_t>(order.size(), 64);
        while (begin < order.size()) {
            const std::size_t end = std::min(order.size(), begin + round);
            std::sort(order.begin() + std::ptrdiff_t(begin), order.begin() + std::ptrdiff_t(end));
            begin = end;
            round *= 2;
        }
        last_ = 0;
        rng_ = Pcg32(seed, 77);
        for (const auto& o : order) insert(o.second);
    }

    /// All points, the 4 super vertices first: input point i is points()[i + 4].
    const std::vector<Vec3d>& points() const { return points_; }
    /// Every live tetrahedron of the tessellation, super ones included (valid adjacency).
    std::vector<Tetrahedron> all_tetrahedra() const {
        std::vector<Tetrahedron> out;
        for (std::size_t i = 0; i < tets_.size(); ++i)
            if (alive_[i]) out.push_back(tets_[i]);
        return out;
    }
    /// Tetrahedra of input points only, vertex indices into the *input* array.
    std::vector<std::array<std::int32_t, 4>> tetrahedra() const {
        std::vector<std::array<std::int32_t, 4>> out;
        for (std::size_t i = 0; i < tets_.size(); ++i) {
            if (!alive_[i]) continue;
            const auto& v = tets_[i].v;
            if (v[0] < super_vertices || v[1] < super_vertices || v[2] < super_vertices || v[3] < super_vertices)
                continue;
            out.push_back({v[0] - super_vertices, v[1] - super_vertices, v[2] - super_vertices, v[3] - super_vertices});
        }
        return out;
    }
    std::size_t duplicate_count() const { return duplicates_; }  ///< Input points skipped as exact duplicates.

private:
    static std::uint32_t spread(std::uint32_t x) {
        x &= 0x3ff;
        x = (x | (x << 16)) & 0x030000ff;
        x = (x | (x << 8)) & 0x0300f00f;
        x = (x | (x << 4)) & 0x030c30c3;
        x = (x | (x << 2)) & 0x09249249;
        return x;
    }
    static std::uint32_t morton(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
        return spread(x) | (spread(y) << 1) | (spread(z) << 2);
    }

    /// Orientation of p against face i of tetrahedron t, positive on the side of v[i].
    int face_orient(const Tetrahedron& t, int i, const Vec3d& p) const {
        std::array<Vec3d, 4> q;
        for (int k = 0; k < 4; ++k) q[std::size_t(k)] = points_[std::size_t(t.v[std::size_t(k)])];
        q[std::size_t(i)] = p;
        return orient3d(q[0], q[1], q[2], q[3]);
    }

    /// Remembering stochastic walk; returns a tetrahedron whose closure contains p.
    std::int32_t locate(const Vec3d& p) {
        std::int32_t cur = last_;
        if (!alive_[std::size_t(cur)]) cur = first_alive();
        std::int32_t prev = -1;
        for (std::size_t steps = 0;; ++steps) {
            const Tetrahedron& t = tets_[std::size_t(cur)];
            const int start = int(rng_.bounded(4));
            std::int32_t next = -1;
            for (int k = 0; k < 4; ++k) {
                const int i = (start + k) & 3;
                const std::int32_t n = t.neighbour[std::size_t(i)];
                if (n == prev && n >= 0) continue;
                if (face_orient(t, i, p) < 0) {
                    next = n;
                    if (n < 0) throw Error("glint::Delaunay: point outside the enclosing tetrahedron");
                    break;
                }
            }
            if (next < 0) return cur;
            prev = cur;
            cur = next;
            if (steps > 4 * tets_.size() + 64) {
                // Cannot happen with exact predicates; fall back to a scan rather than loop.
                for (std::size_t j = 0; j < tets_.size(); ++j) {
                    if (!alive_[j]) continue;
                    bool inside = true;
                    for (int i = 0; i < 4 && inside; ++i) inside = face_orient(tets_[j], i, p) >= 0;
                    if (inside) return std::int32_t(j);
                }
                throw Error("glint::Delaunay: point location failed");
            }
        }
    }

    std::int32_t first_alive() const {
        for (std::size_t j = 0; j < tets_.size(); ++j)
            if (alive_[j]) return std::int32_t(j);
        return 0;
    }

    bool in_conflict(std::int32_t t, const Vec3d& p) const {
        const auto& v = tets_[std::size_t(t)].v;
        return insphere(points_[std::size_t(v[0])], points_[std::size_t(v[1])], points_[std::size_t(v[2])],
                        points_[std::size_t(v[3])], p) > 0;
    }

    void insert(std::int32_t pi) {
        const Vec3d p = points_[std::size_t(pi)];
        const std::int32_t start = locate(p);
        for (std::int32_t v : tets_[std::size_t(start)].v)
            if (points_[std::size_t(v)] == p) {
                ++duplicates_;
                return;
            }
        grow_cavity(start, p);
        created_.clear();
        links_.clear();
        for (std::int32_t c : cavity_) star_faces(c, pi);
        for (std::int32_t c : cavity_) {
            alive_[std::size_t(c)] = 0;
            free_.push_back(c);
        }
        link_star();
        last_ = created_.back();
    }

    /// The cavity: breadth-first search from `start` over strictly conflicting tetrahedra.
    void grow_cavity(std::int32_t start, const Vec3d& p) {
        cavity_.clear();
        cavity_.push_back(start);
        alive_[std::size_t(start)] = 2;  // 2 = in cavity
        for (std::size_t k = 0; k < cavity_.size(); ++k) {
            const Tetrahedron& t = tets_[std::size_t(cavity_[k])];
            for (std::int32_t n : t.neighbour)
                if (n >= 0 && alive_[std::size_t(n)] == 1 && in_conflict(n, p)) {
                    alive_[std::size_t(n)] = 2;
                    cavity_.push_back(n);
                }
        }
    }

    /// One new tetrahedron per boundary face of cavity member c: the face's vertices with
    /// point pi for the vertex opposite it (same orientation as the old tetrahedron); its
    /// faces through pi go to links_ for link_star.
    void star_faces(std::int32_t c, std::int32_t pi) {
        const Tetrahedron old = tets_[std::size_t(c)];
        for (int i = 0; i < 4; ++i) {
            const std::int32_t n = old.neighbour[std::size_t(i)];
            if (n >= 0 && alive_[std::size_t(n)] == 2) continue;
            Tetrahedron nt;
            nt.v = old.v;
            nt.v[std::size_t(i)] = pi;
            nt.neighbour = {-1, -1, -1, -1};
            nt.neighbour[std::size_t(i)] = n;
            const std::int32_t id = allocate(nt);
            if (n >= 0)
                for (auto& x : tets_[std::size_t(n)].neighbour)
                    if (x == c) x = id;
            created_.push_back(id);
            // Faces through p: opposite vertex j != i; key = the other two vertices.
            for (int j = 0; j < 4; ++j) {
                if (j == i) continue;
                std::int32_t a = -1, b = -1;
                for (int k = 0; k < 4; ++k) {
                    if (k == i || k == j) continue;
                    (a < 0 ? a : b) = nt.v[std::size_t(k)];
                }
                if (a > b) std::swap(a, b);
                links_.push_back({(std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b), id, j});
            }
        }
    }

    /// Pairs the new tetrahedra across their faces through the inserted point.
    void link_star() {
        std::sort(links_.begin(), links_.end(), [](const Link& x, const Link& y) { return x.key < y.key; });
        for (std::size_t k = 0; k + 1 < links_.size(); k += 2) {
            const Link& x = links_[k];
            const Link& y = links_[k + 1];
            if (x.key != y.key) throw Error("glint::Delaunay: cavity is not a closed star (internal error)");
            tets_[std::size_t(x.tet)].neighbour[std::size_t(x.face)] = y.tet;
            tets_[std::size_t(y.tet)].neighbour[std::size_t(y.face)] = x.tet;
        }
    }

    std::int32_t allocate(const Tetrahedron& t) {
        // Freed slots are reused only after the cavity is released, so new ids never
        // alias cavity members still being read.
        if (!free_.empty()) {
            const std::int32_t id = free_.back();
            free_.pop_back();
            tets_[std::size_t(id)] = t;
            alive_[std::size_t(id)] = 1;
            return id;
        }
        tets_.push_back(t);
        alive_.push_back(1);
        return std::int32_t(tets_.size() - 1);
    }

    struct Link {
        std::uint64_t key;
        std::int32_t tet;
        int face;
    };

    /// The exact predicates (predicates.hpp) need products of five coordinates or coordinate
    /// differences neither to overflow nor to underflow: every nonzero |coordinate| and every
    /// nonzero difference between two coordinates on an axis must lie in [min_magnitude,
    /// max_magnitude] (the super tetrahedron reaches 1e4 times the extent). Throws otherwise,
    /// naming the point and the value: outside, the empty-sphere property is not guaranteed.
    static constexpr double min_magnitude = 1e-50, max_magnitude = 1e50;
    static void check_range(std::span<const Vec3<T>> pts) {
        auto fail = [](std::size_t i, int axis, double value, const char* what) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "%.3g", value);
            throw Error("glint::Delaunay: point " + std::to_string(i) + ", axis " + std::to_string(axis) + ": " + what +
                        " " + buf + " is outside [1e-50, 1e50] (or 0), the range of the exact predicates; "
                        "rescale the points");
        };
        std::vector<std::pair<double, std::size_t>> axis(pts.size());
        for (int k = 0; k < 3; ++k) {
            for (std::size_t i = 0; i < pts.size(); ++i) {
                const double x = double(pts[i][k]);
                if (x != 0.0 && !(std::abs(x) >= min_magnitude && std::abs(x) <= max_magnitude))
                    fail(i, k, x, "coordinate");
                axis[i] = {x, i};
            }
            std::sort(axis.begin(), axis.end());
            for (std::size_t i = 1; i < axis.size(); ++i) {
                const double gap = axis[i].first - axis[i - 1].first;
                if (gap != 0.0 && !(gap >= min_magnitude)) fail(axis[i].second, k, gap, "gap to the nearest other coordinate");
            }
        }
    }

    std::vector<Vec3d> points_;
    std::vector<Tetrahedron> tets_;
    std::vector<std::uint8_t> alive_;  // 0 dead, 1 alive, 2 in the current cavity
    std::vector<std::int32_t> free_, cavity_, created_;
    std::vector<Link> links_;
    std::int32_t last_ = 0;
    Pcg32 rng_;
    std::size_t duplicates_ = 0;
};

}  // namespace glint
