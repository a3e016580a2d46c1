// glint/occluders/spheres.hpp: occluder-sphere generation from a triangle mesh.
//
// Szécsi 2009, §5.2: sample points on the surface, tetrahedralize them
// (delaunay.hpp), and take the circumspheres of the inner tetrahedra as a tight initial set;
// then merge pairs until the target count is reached.
// - Inner tetrahedra, section 5.2.1: a tetrahedron is inner when at each of
//   its four vertices the angle between the sphere normal (vertex - circumcentre) and the
//   surface normal is below pi/2. Surface normals are the sampled triangles' geometric
//   normals, oriented outward by the sign of the mesh's signed volume. glint also drops
//   circumspheres that are not finite or larger than the mesh's bounding sphere (slivers
//   of flat regions when sampling is sparse).
// - Merging, section 5.2.2: repeatedly merge the closest pair under
//   D1 = d or D2 = d + r - R (R >= r). Every sphere remembers its best partner; a merge
//   recomputes partners only for the new sphere and for spheres whose partner was merged.
//   This still finds the globally closest pair: for the closest pair (i, j) the younger of
//   the two had its partner computed when both existed, so its record is <= D(i, j).
//   Partners are found in a uniform grid of sphere centres (Szécsi 2009 suggests a kd-tree)
//   that is updated by each merge and rebuilt whenever the live count halves.
// - New radius, section 5.2.3: R_new = sqrt(A(R, r, d) / 4 pi), A from gssa.hpp (GssaModel).
// - New centre, section 5.2.4: the centres weighted by the hull caps
//   S_R and S_r of section 5.2.3.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <span>
#include <string>
#include <vector>

#include <glint/core/aabb.hpp>
#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/random.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/occluders/delaunay.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/occluders/gssa.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/traversal.hpp>

namespace glint {

/// An occluder sphere, world space.
template <Scalar T>
struct Sphere {
    Vec3<T> centre{0};  ///< Centre, world coordinates.
    T radius = 0;       ///< Radius, world units (>= 0).
};

/// Pair distance of the merge (Szécsi 2009, §5.2.2): d1 = d (centre distance), d2 = d + r - R
/// (R >= r: how far the smaller sphere reaches out of the larger).
enum class MergeDistance { d1, d2 };

/// Options of occluder generation. samples = 0 picks max(10000, 4 * triangles) capped at
/// 50000. calibrate: after merging, scale all radii by one factor so that the set's hit
/// probability for isotropic random lines through the mesh's bounding ball equals the
/// mesh's, measured with calibration_lines lines (see calibrate_radii).
struct OccluderOptions {
    std::size_t samples = 0;                     ///< Surface samples; 0: automatic (see above).
    MergeDistance distance = MergeDistance::d2;  ///< Which pair the merger takes next.
    GssaModel gssa = GssaModel::fitted;          ///< Area model that gives a merged sphere's radius.
    std::uint64_t seed = 1;                      ///< Seed of sampling, insertion order and calibration lines.
    bool calibrate = true;                       ///< Scale radii to match the mesh's hit probability.
    std::size_t calibration_lines = 20000;       ///< Random lines per hit probability measurement.
};

/// Circumcentre and radius of a tetrahedron (double; false when degenerate).
inline bool circumsphere(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d, Vec3d& centre, double& radius) {
    const Vec3d ba = b - a, ca = c - a, da = d - a;
    const double den = 2.0 * glm::dot(ba, glm::cross(ca, da));
    if (den == 0) return false;
    const Vec3d num = glm::dot(ba, ba) * glm::cross(ca, da) + glm::dot(ca, ca) * glm::cross(da, ba) +
                      glm::dot(da, da) * glm::cross(ba, ca);
    const Vec3d off = num / den;
    centre = a + off;
    radius = glm::length(off);
    return all_finite(centre) && std::isfinite(radius);
}

/// Surface samples with outward normals: area-weighted uniform points on the triangles.
template <Scalar T>
void sample_surface(std::span<const TriangleVertices<T>> mesh, std::size_t n, std::uint64_t seed,
                    std::vector<Vec3d>& points, std::vector<Vec3d>& normals) {
    std::vector<double> cdf;
    cdf.reserve(mesh.size());
    double total = 0, volume = 0;
    for (const auto& t : mesh) {
        if (!all_finite(t[0]) || !all_finite(t[1]) || !all_finite(t[2]))
            throw Error("glint::sample_surface: mesh has a non-finite vertex");
        const Vec3d a(t[0]), b(t[1]), c(t[2]);
        total += glm::length(glm::cross(b - a, c - a));
        volume += glm::dot(a, glm::cross(b, c));
        cdf.push_back(total);
    }
    if (!(total > 0)) throw Error("glint::sample_surface: mesh has no area");
    const double flip = volume < 0 ? -1.0 : 1.0;  // outward normals for either winding
    Pcg32 rng(seed, 3);
    points.resize(n);
    normals.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
        const double x = rng.uniform<double>() * total;
        const auto i = std::min<std::size_t>(std::size_t(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin()),
                                             mesh.size() - 1);
        const Vec3d a(mesh[i][0]), b(mesh[i][1]), c(mesh[i][2]);
        double u = rng.uniform<double>(), v = rng.uniform<double>();
        if (u + v > 1) u = 1 - u, v = 1 - v;
        points[k] = a + u * (b - a) + v * (c - a);
        normals[k] = flip * safe_normalize(glm::cross(b - a, c - a));
    }
}

/// The initial sphere set of Szécsi 2009, §5.2-5.2.1: circumspheres of inner tetrahedra.
template <Scalar T>
std::vector<Sphere<T>> initial_occluders(std::span<const TriangleVertices<T>> mesh, const OccluderOptions& opt = {}) {
    if (mesh.empty()) throw Error("glint::initial_occluders: empty mesh");
    const std::size_t n = opt.samples ? opt.samples : std::clamp<std::size_t>(4 * mesh.size(), 10000, 50000);
    std::vector<Vec3d> pts, nrm;
    sample_surface(mesh, n, opt.seed, pts, nrm);
    AABB<double> box;
    for (const auto& p : pts) box.extend(p);
    const double limit = 0.5 * glm::length(box.extent());
    const Delaunay<double> dt(std::span<const Vec3d>(pts), opt.seed);
    std::vector<Sphere<T>> out;
    for (const auto& t : dt.tetrahedra()) {
        Vec3d c;
        double r;
        const Vec3d &a = pts[std::size_t(t[0])], &b = pts[std::size_t(t[1])], &cc = pts[std::size_t(t[2])],
                    &d = pts[std::size_t(t[3])];
        if (!circumsphere(a, b, cc, d, c, r) || !(r > 0) || r > limit) continue;
        bool inner = true;
        for (int k = 0; k < 4 && inner; ++k)
            inner = glm::dot(pts[std::size_t(t[std::size_t(k)])] - c, nrm[std::size_t(t[std::size_t(k)])]) > 0;
        if (inner) out.push_back({Vec3<T>(c), T(r)});
    }
    return out;
}

/// Merges the pair (a, b) into one sphere of equal GSSA at the cap-weighted centre.
template <Scalar T>
Sphere<T> merge_pair(const Sphere<T>& a, const Sphere<T>& b, GssaModel model = GssaModel::fitted) {
    const double d = glm::length(Vec3d(a.centre) - Vec3d(b.centre));
    const double R = a.radius, r = b.radius;
    const double A = gssa<double>(model, R, r, d);
    double wa, wb;
    gssa_cap_weights<double>(R, r, d, wa, wb);
    const double sw = wa + wb;
    const Vec3d c = sw > 0 ? (wa * Vec3d(a.centre) + wb * Vec3d(b.centre)) / sw : Vec3d(a.centre);
    return {Vec3<T>(c), T(std::sqrt(A / (4 * pi<double>)))};
}

/// Greedy closest-pair merging (Szécsi 2009, §5.2.2) that can be stopped at several counts.
template <Scalar T>
class SphereMerger {
public:
    /// Takes the initial spheres and finds every sphere's closest partner. Throws Error for a
    /// non-finite centre or radius, or a negative radius.
    SphereMerger(std::vector<Sphere<T>> initial, MergeDistance distance = MergeDistance::d2,
                 GssaModel model = GssaModel::fitted)
        : s_(std::move(initial)), distance_(distance), model_(model) {
        for (const auto& s : s_)
            if (!all_finite(s.centre) || !(s.radius >= 0) || !std::isfinite(s.radius))
                throw Error("glint::SphereMerger: sphere with non-finite centre or radius");
        alive_.assign(s_.size(), 1);
        live_ = s_.size();
        partner_.assign(s_.size(), -1);
        stamp_.assign(s_.size(), 0);
        partner_of_.resize(s_.size());
        for (const auto& s : s_) rmax_ = std::max(rmax_, double(s.radius));
        rebuild_grid();
        for (std::size_t i = 0; i < s_.size(); ++i) update_partner(std::int32_t(i));
    }

    std::size_t size() const { return live_; }     ///< Spheres alive now.
    std::size_t merges() const { return merges_; } ///< Merges done so far.

    /// Merges closest pairs until at most `target` spheres remain (target >= 1).
    void reduce_to(std::size_t target) {
        target = std::max<std::size_t>(target, 1);
        while (live_ > target && !heap_.empty()) {
            const Entry e = heap_.top();
            heap_.pop();
            if (!alive_[std::size_t(e.i)] || !alive_[std::size_t(e.j)] || stamp_[std::size_t(e.i)] != e.stamp) continue;
            merge(e.i, e.j);
        }
    }

    /// The spheres alive now (a copy, in creation order).
    std::vector<Sphere<T>> spheres() const {
        std::vector<Sphere<T>> out;
        out.reserve(live_);
        for (std::size_t i = 0; i < s_.size(); ++i)
            if (alive_[i]) out.push_back(s_[i]);
        return out;
    }

    /// The merge distance of (a, b) under this merger's MergeDistance (d2: d - |R - r|).
    double pair_distance(const Sphere<T>& a, const Sphere<T>& b) const {
        const double d = glm::length(Vec3d(a.centre) - Vec3d(b.centre));
        return distance_ == MergeDistance::d1 ? d : d - std::abs(double(a.radius) - double(b.radius));
    }

private:
    struct Entry {
        double dist;
        std::int32_t i, j;
        std::uint32_t stamp;
        bool operator<(const Entry& o) const { return dist > o.dist; }  // min-heap
    };

    void merge(std::int32_t i, std::int32_t j) {
        const Sphere<T> m = merge_pair(s_[std::size_t(i)], s_[std::size_t(j)], model_);
        grid_remove(i);
        grid_remove(j);
        alive_[std::size_t(i)] = alive_[std::size_t(j)] = 0;
        const auto k = std::int32_t(s_.size());
        s_.push_back(m);
        alive_.push_back(1);
        partner_.push_back(-1);
        stamp_.push_back(0);
        partner_of_.emplace_back();
        next_.push_back(-1);
        prev_.push_back(-1);
        cell_.push_back(0);
        rmax_ = std::max(rmax_, double(m.radius));
        --live_;
        ++merges_;
        if (live_ * 2 < grid_count_) {
            rebuild_grid();
        } else {
            grid_insert(k);
        }
        update_partner(k);
        for (std::int32_t gone : {i, j}) {
            std::vector<std::int32_t> list;
            list.swap(partner_of_[std::size_t(gone)]);
            for (std::int32_t s : list)
                if (alive_[std::size_t(s)] && partner_[std::size_t(s)] == gone) update_partner(s);
        }
    }

    void update_partner(std::int32_t i) {
        double best = infinity<double>;
        const std::int32_t j = nearest(i, best);
        partner_[std::size_t(i)] = j;
        ++stamp_[std::size_t(i)];
        if (j >= 0) {
            partner_of_[std::size_t(j)].push_back(i);
            heap_.push({best, i, j, stamp_[std::size_t(i)]});
        }
    }

    // ---- uniform grid of live centres ----
    void rebuild_grid() {
        AABB<double> b;
        for (std::size_t i = 0; i < s_.size(); ++i)
            if (alive_[i]) b.extend(Vec3d(s_[i].centre));
        if (b.empty()) b.extend(Vec3d(0));
        lo_ = b.lo;
        const Vec3d e = glm::max(b.extent(), Vec3d(1e-12 * (1 + glm::length(b.lo))));
        const double cells = std::max<double>(1, double(live_));
        h_ = std::cbrt(e.x * e.y * e.z / cells);
        h_ = std::max({h_, e.x / 256, e.y / 256, e.z / 256, 1e-300});
        // At most about 2 cells per live sphere (flat sets would otherwise get 256^3 cells).
        for (;;) {
            for (int a = 0; a < 3; ++a) dim_[a] = std::max(1, std::min(256, int(std::ceil(e[a] / h_))));
            if (double(dim_[0]) * dim_[1] * dim_[2] <= 2 * cells + 8) break;
            h_ *= 1.25;
        }
        head_.assign(std::size_t(dim_[0]) * std::size_t(dim_[1]) * std::size_t(dim_[2]), -1);
        cell_rmin_.assign(head_.size(), infinity<double>);
        cell_rmax_.assign(head_.size(), -infinity<double>);
        rmin_ = infinity<double>;
        next_.assign(s_.size(), -1);
        prev_.assign(s_.size(), -1);
        cell_.assign(s_.size(), 0);
        for (std::size_t i = 0; i < s_.size(); ++i)
            if (alive_[i]) grid_insert(std::int32_t(i));
        grid_count_ = live_;
    }
    std::array<int, 3> cell_of(const Vec3d& p) const {
        std::array<int, 3> c;
        for (int a = 0; a < 3; ++a) c[std::size_t(a)] = std::clamp(int(std::floor((p[a] - lo_[a]) / h_)), 0, dim_[a] - 1);
        return c;
    }
    std::size_t flat(int x, int y, int z) const {
        return (std::size_t(z) * std::size_t(dim_[1]) + std::size_t(y)) * std::size_t(dim_[0]) + std::size_t(x);
    }
    void grid_insert(std::int32_t i) {
        const auto c = cell_of(Vec3d(s_[std::size_t(i)].centre));
        const std::size_t f = flat(c[0], c[1], c[2]);
        cell_[std::size_t(i)] = f;
        const double r = s_[std::size_t(i)].radius;
        cell_rmin_[f] = std::min(cell_rmin_[f], r);
        cell_rmax_[f] = std::max(cell_rmax_[f], r);
        rmin_ = std::min(rmin_, r);
        prev_[std::size_t(i)] = -1;
        next_[std::size_t(i)] = head_[f];
        if (head_[f] >= 0) prev_[std::size_t(head_[f])] = i;
        head_[f] = i;
    }
    void grid_remove(std::int32_t i) {
        const std::size_t f = cell_[std::size_t(i)];
        const std::int32_t p = prev_[std::size_t(i)], n = next_[std::size_t(i)];
        if (p >= 0) next_[std::size_t(p)] = n;
        else head_[f] = n;
        if (n >= 0) prev_[std::size_t(n)] = p;
    }

    /// Best partner of sphere i under the merge distance: grid rings of growing Chebyshev
    /// radius k, stopped when the ring's lower bound (k - 1) h (minus the largest possible
    /// radius difference for D2, since D2 = d - |r_i - r_j|) cannot beat the best found; a
    /// cell is skipped when its box distance minus its own radius range cannot.
    std::int32_t nearest(std::int32_t i, double& best) const {
        const Sphere<T>& si = s_[std::size_t(i)];
        const auto c = cell_of(Vec3d(si.centre));
        const double ri = si.radius;
        const bool d2 = distance_ == MergeDistance::d2;
        const double slack = d2 ? std::max(rmax_ - ri, ri - rmin_) : 0.0;
        const Vec3d pc(si.centre);
        const int kmax = std::max({dim_[0], dim_[1], dim_[2]});
        std::int32_t arg = -1;
        best = infinity<double>;
        for (int k = 0; k <= kmax; ++k) {
            if (double(k - 1) * h_ - slack >= best) break;
            auto visit = [&](int x, int y, int z) {
                if (x < 0 || y < 0 || z < 0 || x >= dim_[0] || y >= dim_[1] || z >= dim_[2]) return;
                const std::size_t f = flat(x, y, z);
                if (head_[f] < 0) return;
                const Vec3d clo = lo_ + h_ * Vec3d(x, y, z);
                const Vec3d gap = glm::max(glm::max(clo - pc, pc - (clo + Vec3d(h_))), Vec3d(0));
                const double cs = d2 ? std::max(cell_rmax_[f] - ri, ri - cell_rmin_[f]) : 0.0;
                if (glm::length(gap) - cs > best) return;
                for (std::int32_t j = head_[f]; j >= 0; j = next_[std::size_t(j)]) {
                    if (j == i) continue;
                    const double dd = pair_distance(si, s_[std::size_t(j)]);
                    if (dd < best || (dd == best && j < arg)) best = dd, arg = j;
                }
            };
            for (int dx = -k; dx <= k; ++dx)
                for (int dy = -k; dy <= k; ++dy) {
                    if (std::max(std::abs(dx), std::abs(dy)) == k) {
                        for (int dz = -k; dz <= k; ++dz) visit(c[0] + dx, c[1] + dy, c[2] + dz);
                    } else {
                        visit(c[0] + dx, c[1] + dy, c[2] - k);
                        if (k) visit(c[0] + dx, c[1] + dy, c[2] + k);
                    }
                }
        }
        return arg;
    }

    std::vector<Sphere<T>> s_;
    std::vector<std::uint8_t> alive_;
    std::vector<std::int32_t> partner_;
    std::vector<std::uint32_t> stamp_;
    std::vector<std::vector<std::int32_t>> partner_of_;
    std::priority_queue<Entry> heap_;
    MergeDistance distance_;
    GssaModel model_;
    std::size_t live_ = 0, merges_ = 0, grid_count_ = 0;
    double rmax_ = 0;
    // grid
    Vec3d lo_{0};
    double h_ = 1;
    std::array<int, 3> dim_{1, 1, 1};
    std::vector<std::int32_t> head_, next_, prev_;
    std::vector<std::size_t> cell_;
    std::vector<double> cell_rmin_, cell_rmax_;  // radius ranges, conservative until rebuild
    double rmin_ = infinity<double>;
};

/// The bounding ball random lines are drawn through: the mesh box's centre and half diagonal.
template <Scalar T>
void mesh_ball(std::span<const TriangleVertices<T>> mesh, Vec3<T>& centre, T& radius) {
    AABB<T> b;
    for (const auto& t : mesh)
        for (const auto& v : t) b.extend(v);
    centre = b.center();
    radius = T(0.5) * glm::length(b.extent());
}

/// Fraction of `lines` isotropic random lines through the ball (centre, radius) that hit the
/// mesh (any-hit through a kd-tree of trees/).
template <Scalar T>
double mesh_hit_fraction(std::span<const TriangleVertices<T>> mesh, const Vec3<T>& centre, T radius,
                         std::size_t lines, std::uint64_t seed) {
    const KdTree<T, MollerTrumbore<T>, PointerLayout> tree(mesh);
    Pcg32 rng(seed);
    std::size_t hits = 0;
    for (std::size_t l = 0; l < lines; ++l) {
        Vec3<T> p, w;
        random_line(rng, centre, radius, p, w);
        Ray<T> ray;
        ray.origin = p - T(1.01) * radius * w;
        ray.direction = w;
        ray.tmax = T(2.02) * radius;
        hits += tree.any_hit(ray);
    }
    return lines ? double(hits) / double(lines) : 0.0;
}

/// Radius calibration (a glint addition; Szécsi 2009, §5.2.3, rejects "correct[ing]
/// the radii by some arbitrary factor", and this factor is not arbitrary: it is the one that
/// makes the set's hit probability equal the target, the stated goal of §5.2). Pairwise GSSA
/// preservation assumes the rest of the set shadows both predecessors alike; on long thin
/// objects it overestimates the set's shadow more with every merge (docs/occluders.md lists
/// both numbers). For each line the smallest scale at which it
/// hits a sphere is min_i dist(line, c_i) / r_i; the factor is the target quantile of these.
/// Returns the factor applied.
template <Scalar T>
double calibrate_radii(std::vector<Sphere<T>>& set, double target_fraction, const Vec3<T>& centre, T radius,
                       std::size_t lines, std::uint64_t seed) {
    if (set.empty() || lines == 0) return 1.0;
    std::vector<double> need(lines);
    Pcg32 rng(seed);
    for (std::size_t l = 0; l < lines; ++l) {
        Vec3<T> p, w;
        random_line(rng, centre, radius, p, w);
        double best = infinity<double>;
        for (const auto& s : set) {
            const Vec3d v = Vec3d(s.centre - p);
            const double along = glm::dot(v, Vec3d(w));
            const double d2 = std::max(0.0, glm::dot(v, v) - along * along);
            if (s.radius > 0) best = std::min(best, std::sqrt(d2) / double(s.radius));
        }
        need[l] = best;
    }
    const auto k = std::size_t(std::llround(std::clamp(target_fraction, 0.0, 1.0) * double(lines)));
    if (k == 0) return 1.0;
    std::nth_element(need.begin(), need.begin() + std::ptrdiff_t(k - 1), need.end());
    const double f = need[k - 1];
    if (!(f > 0) || !std::isfinite(f)) return 1.0;
    for (auto& s : set) s.radius = T(double(s.radius) * f);
    return f;
}

/// Occluder sets of several sizes from one generation (targets in any order): the initial
/// inner circumspheres merged down through each target, calibrated if opt.calibrate.
template <Scalar T>
std::vector<std::vector<Sphere<T>>> generate_occluder_levels(std::span<const TriangleVertices<T>> mesh,
                                                             std::span<const std::size_t> targets,
                                                             const OccluderOptions& opt = {}) {
    std::vector<std::size_t> order(targets.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return targets[a] > targets[b]; });
    SphereMerger<T> m(initial_occluders(mesh, opt), opt.distance, opt.gssa);
    Vec3<T> c;
    T radius;
    mesh_ball(mesh, c, radius);
    const double p = opt.calibrate ? mesh_hit_fraction(mesh, c, radius, opt.calibration_lines, opt.seed + 1000) : 0.0;
    std::vector<std::vector<Sphere<T>>> out(targets.size());
    for (std::size_t i : order) {
        m.reduce_to(targets[i]);
        out[i] = m.spheres();
        if (opt.calibrate) calibrate_radii(out[i], p, c, radius, opt.calibration_lines, opt.seed + 1000);
    }
    return out;
}

/// Generated occluders: the initial set of inner circumspheres merged down to `target`.
template <Scalar T>
std::vector<Sphere<T>> generate_occluders(std::span<const TriangleVertices<T>> mesh, std::size_t target,
                                          const OccluderOptions& opt = {}) {
    const std::size_t t[1] = {target};
    return std::move(generate_occluder_levels(mesh, std::span<const std::size_t>(t, 1), opt)[0]);
}

/// Probability that an isotropic random line meeting the ball (centre, radius) hits a sphere
/// of the set; `lines` lines from rng (the same stream gives the same lines to a mesh test).
template <Scalar T>
double sphere_set_hit_fraction(std::span<const Sphere<T>> set, const Vec3<T>& centre, T radius, std::size_t lines,
                               std::uint64_t seed) {
    Pcg32 rng(seed);
    std::size_t hits = 0;
    for (std::size_t l = 0; l < lines; ++l) {
        Vec3<T> p, w;
        random_line(rng, centre, radius, p, w);
        for (const auto& s : set) {
            const Vec3<T> v = s.centre - p;
            const T along = glm::dot(v, w);
            if (glm::dot(v, v) - along * along <= s.radius * s.radius) {
                ++hits;
                break;
            }
        }
    }
    return double(hits) / double(lines);
}

}  // namespace glint
