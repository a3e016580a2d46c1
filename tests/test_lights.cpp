// Tests for glint/lights: the point emitters' profiles integrate to the power they state, and
// bad lights are rejected by index.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>

#include <glint/lights/light.hpp>
#include <glint/sampling/warps.hpp>

using namespace glint;

namespace {

/// The solid-angle integral of a light's falloff on a fine stratified grid of the sphere.
double integrated_falloff(const PointLight<double>& l) {
    const int n = 1024;
    double sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            sum += l.falloff(square_to_uniform_sphere(Vec2<double>((i + 0.5) / n, (j + 0.5) / n)));
    return sum * 4 * pi<double> / (double(n) * n);
}

}  // namespace

TEST_CASE("each point light's measure() is the integral of its falloff") {
    const Vec3<double> p(0), axis = safe_normalize(Vec3<double>(1, 2, -3));
    const PointLight<double> lights[] = {
        PointLight<double>::isotropic(p, Rgb<double>(1)),
        PointLight<double>::oriented(p, axis, Rgb<double>(1)),
        PointLight<double>::spot(p, axis, Rgb<double>(1), 0.6, 0.3),
        PointLight<double>::spot(p, axis, Rgb<double>(1), 1.2, 1.2),
    };
    for (const auto& l : lights) {
        CAPTURE(int(l.kind));
        // The grid's error is O(1/n) at the cone's edge: 1e-3 relative is 30x what n = 1024 leaves.
        CHECK(integrated_falloff(l) == doctest::Approx(l.measure()).epsilon(1e-3));
        CHECK(l.falloff(-axis) == (l.kind == PointLightKind::isotropic ? 1.0 : 0.0));
    }
}

TEST_CASE("a spot light is I cos(theta) inside its inner cone, dark outside its outer one") {
    const auto s = PointLight<float>::spot(Vec3<float>(0), Vec3<float>(0, 0, -1), Rgb<float>(2), 0.5f, 0.25f);
    CHECK(s.falloff(Vec3<float>(0, 0, -1)) == 1.0f);
    CHECK(s.falloff(Vec3<float>(std::sin(0.2f), 0, -std::cos(0.2f))) == doctest::Approx(std::cos(0.2f)));
    CHECK(s.falloff(Vec3<float>(std::sin(0.55f), 0, -std::cos(0.55f))) == 0.0f);
    const float mid = s.falloff(Vec3<float>(std::sin(0.4f), 0, -std::cos(0.4f)));
    CHECK(mid > 0.0f);
    CHECK(mid < std::cos(0.4f));
    CHECK(s.cos_emission() == doctest::Approx(std::cos(0.5f)));
}

TEST_CASE("invalid point lights are rejected, naming the light") {
    auto l = PointLight<float>::spot(Vec3<float>(0), Vec3<float>(0, 0, 1), Rgb<float>(1), 0.5f, 0.2f);
    CHECK_NOTHROW(l.validate(0));
    l.axis = Vec3<float>(0);
    CHECK_THROWS_WITH_AS(l.validate(7), doctest::Contains("light 7: axis"), Error);
    l = PointLight<float>::isotropic(Vec3<float>(0, NAN, 0), Rgb<float>(1));
    CHECK_THROWS_WITH_AS(l.validate(3), doctest::Contains("light 3: position"), Error);
    l = PointLight<float>::isotropic(Vec3<float>(0), Rgb<float>(-1));
    CHECK_THROWS_WITH_AS(l.validate(2), doctest::Contains("light 2: intensity"), Error);
    l = PointLight<float>::spot(Vec3<float>(0), Vec3<float>(0, 0, 1), Rgb<float>(1), 0.5f, 0.2f);
    std::swap(l.cos_inner, l.cos_outer);
    CHECK_THROWS_WITH_AS(l.validate(1), doctest::Contains("light 1: spot cones"), Error);
}

// ---- The stochastic light tree and the selectors of MisDirect (lights/light_tree.hpp) ----

#include <glint/lights/light_tree.hpp>
#include <glint/lights/scenes.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/named_render.hpp>

namespace {

/// A small many-light scene with every kind of emitter: the LIE hall (100 point lights,
/// pillars and screens) plus 24 spots and 24 cosine lights, and (with areas) 6 polygon lights.
Scene<float> mixed_scene(bool areas) {
    Scene<float> s = lie_hall_scene<float>(6);
    using V = Vec3<float>;
    for (int i = 0; i < 24; ++i) {
        const float x = -9.0f + 0.78f * float(i);
        s.point_lights.push_back(PointLight<float>::spot(V(x, 4.0f, -9.9f), V(0.1f, -0.8f, 1), Rgb<float>(3, 2.5f, 2), 0.6f, 0.3f));
        s.point_lights.push_back(PointLight<float>::oriented(V(x, 5.99f, 3.0f), V(0, -1, 0), Rgb<float>(0.6f, 0.7f, 0.9f)));
    }
    if (areas) {
        const auto glow = s.add_material(Material<float>::lambertian(Rgb<float>(0.5f), Rgb<float>(2.0f, 1.8f, 1.5f)));
        for (int i = 0; i < 6; ++i) {
            const float x = -7.5f + 3.0f * float(i), z = i % 2 ? 4.0f : -5.0f;
            s.add_quad(V(x, 5.95f, z), V(x + 0.8f, 5.95f, z), V(x + 0.8f, 5.95f, z + 0.8f), V(x, 5.95f, z + 0.8f), glow);
        }
    }
    return s;
}

/// The shading points the camera's rays meet through an nx x ny grid of the image, each with
/// its BRDF (kept alive in `brdfs`).
struct ShadingPoints {
    std::vector<Frame<float>> frames;
    std::vector<SurfaceBrdf<float>> brdfs;
    std::vector<ShadingPoint<float>> points;
    ShadingPoints(const Scene<float>& s, const DefaultAccel& accel, int nx, int ny) {
        frames.reserve(std::size_t(nx * ny)), brdfs.reserve(std::size_t(nx * ny));
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                const Ray<float> ray = s.camera.ray((float(i) + 0.5f) / float(nx), (float(j) + 0.5f) / float(ny), 1.0f);
                StoreHit<float> hit;
                if (!accel.closest_hit(ray, hit)) continue;
                const Vec3<float> ng = s.normal(hit.id);
                const Vec3<float> n = glm::dot(ng, ray.direction) < 0.0f ? ng : -ng;
                const SurfacePoint<float> p = surface_point(s, hit);
                frames.push_back(Frame<float>::from_normal(n));
                brdfs.emplace_back(s.materials[s.material_of[hit.id]], frames.back().to_local(-ray.direction));
                points.push_back({p.x, p.err, n, frames.back(), &brdfs.back()});
            }
    }
};

/// The chi-square statistic's 1 - 3e-5 quantile (z = 4) for k degrees of freedom
/// (Wilson and Hilferty 1931).
double chi2_bound(double k) {
    const double a = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - a + 4.0 * std::sqrt(a), 3.0);
}

}  // namespace

TEST_CASE("light tree: builds the same tree every time, one leaf per emitter, the root holding all the power") {
    const Scene<float> s = mixed_scene(true);
    const auto bounds = scene_light_bounds(s);
    const LightTree<float> a(bounds), b(bounds);
    CHECK(a == b);
    REQUIRE(a.size() == bounds.size());
    CHECK(a.nodes().size() == 2 * bounds.size() - 1);
    std::vector<int> seen(bounds.size(), 0);
    double phi = 0;
    for (const auto& n : a.nodes())
        if (n.second < 0) ++seen[std::size_t(n.light)];
    for (const auto& l : bounds) phi += l.phi;
    CHECK(std::count(seen.begin(), seen.end(), 1) == std::ptrdiff_t(bounds.size()));
    CHECK(double(a.nodes()[0].bounds.phi) == doctest::Approx(phi).epsilon(1e-5));
    std::vector<LightBounds<float>> bad(bounds);
    bad[5].box.lo.x = NAN;
    CHECK_THROWS_WITH_AS(LightTree<float>{bad}, doctest::Contains("emitter 5"), Error);
}

TEST_CASE("light tree: probability() plus the dead-end share sums to 1 and equals how often pick() returns each light") {
    // A descent may reach a node whose children both have importance 0 at x (the parent's
    // bounds are looser than theirs): pick() then returns no light (probability 0), as
    // pbrt-v4's BVHLightSampler does; unbiased, since no light below can reach x. So the
    // probabilities sum to 1 minus that share, which is a bin of the chi-square test.
    const Scene<float> s = mixed_scene(true);
    const DefaultAccel accel(s.triangles);
    const LightTree<float> tree(scene_light_bounds(s));
    const ShadingPoints sp(s, accel, 3, 2);
    REQUIRE(sp.points.size() == 6);
    RandomSampler<float> rng(7);
    const int n = 60000;
    int exact_sums = 0, total_bins = 0;
    for (const auto& p : sp.points) {
        std::vector<double> prob(tree.size() + 1);  // the last: no light
        double sum = 0;
        for (std::size_t i = 0; i < tree.size(); ++i) sum += prob[i] = tree.probability(p.x, p.n, i);
        CHECK(sum <= 1.0 + 1e-5);
        prob.back() = std::max(0.0, 1.0 - sum);
        exact_sums += sum > 1.0 - 1e-5;
        std::vector<double> count(prob.size(), 0.0);
        double mismatch = 0;
        for (int k = 0; k < n; ++k) {
            const LightPick<float> pick = tree.pick(p.x, p.n, rng.get_1d());
            if (!(pick.probability > 0.0f)) {
                count.back() += 1;
                continue;
            }
            count[pick.index] += 1;
            mismatch = std::max(mismatch, std::abs(double(pick.probability) / prob[pick.index] - 1.0));
        }
        CHECK(mismatch < 1e-4);
        // Chi-square over the bins expected at least 5 times, the rest pooled in one bin.
        double chi2 = 0, rest_e = 0, rest_o = 0;
        int bins = 0;
        for (std::size_t i = 0; i < prob.size(); ++i) {
            const double e = prob[i] * n;
            if (e < 5) {
                rest_e += e, rest_o += count[i];
                continue;
            }
            chi2 += (count[i] - e) * (count[i] - e) / e, ++bins;
        }
        if (rest_e >= 5) chi2 += (rest_o - rest_e) * (rest_o - rest_e) / rest_e, ++bins;
        CAPTURE(bins);
        total_bins += bins;
        if (bins > 1) CHECK(chi2 < chi2_bound(bins - 1));
    }
    CHECK(total_bins > 60);  // the test sees many lights, not one or two per point
    CHECK(exact_sums >= 1);  // where no descent dead-ends, the probabilities sum to 1
}

TEST_CASE("light tree and power selection: MisDirect's point-light estimate equals every light's shadow ray within standard errors") {
    const Scene<float> s = mixed_scene(false);  // point lights only: the light samples are the whole direct light
    const DefaultAccel accel(s.triangles);
    const ShadingPoints sp(s, accel, 4, 3);
    RayQueries<DefaultAccel> queries(accel);
    RandomSampler<float> rng(11);
    const int n = 3000;
    for (const LightSelection how : {LightSelection::power, LightSelection::tree}) {
        const MisDirect<float> mis(s, PathTracerSettings<float>{}, how);
        int checked = 0;
        for (const auto& p : sp.points) {
            const double exact = all_point_lights(std::span<const PointLight<float>>(s.point_lights), p, queries).luminance();
            double sum = 0, sum2 = 0;
            for (int k = 0; k < n; ++k) {
                const double x = mis.estimate(p, rng, queries, nullptr).luminance();
                sum += x, sum2 += x * x;
            }
            const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
            CAPTURE(int(how));
            CAPTURE(exact);
            CHECK(std::abs(mean - exact) <= 4 * se + 1e-6 * exact);
            checked += exact > 0;
        }
        CHECK(checked >= 10);
    }
}

TEST_CASE("MisDirect with the light tree: the image mean agrees with power selection, light-only and BRDF-only estimates") {
    const Scene<float> s = mixed_scene(true);
    const DefaultAccel accel(s.triangles);
    auto mean_of = [&](const char* direct, int spp, double& se) {
        NamedRender<float> o;
        o.image.width = o.image.height = 10;
        o.image.spp = spp;
        o.image.threads = 2;
        o.direct = direct;
        o.seed = 3;
        const RenderResult r = render_named(s, accel, o);
        double m = 0, v = 0;
        for (std::size_t i = 0; i < r.image.size(); ++i) m += r.image.pixels[i].luminance(), v += r.variance.pixels[i].luminance();
        const double np = double(r.image.size());
        se = std::sqrt(v) / np;
        return m / np;
    };
    double se_tree, se_power, se_light, se_brdf;
    const double tree = mean_of("tree", 64, se_tree), power = mean_of("mis", 64, se_power);
    const double light = mean_of("importance", 16, se_light), brdf = mean_of("brdf", 16, se_brdf);
    CAPTURE(tree);
    CAPTURE(se_tree);
    CHECK(std::abs(tree - power) < 4 * std::hypot(se_tree, se_power));
    CHECK(std::abs(tree - light) < 4 * std::hypot(se_tree, se_light));
    CHECK(std::abs(tree - brdf) < 4 * std::hypot(se_tree, se_brdf));
    CHECK(se_tree < 0.05 * tree);  // the comparisons above are not vacuous
}

// ---- Local illumination environments (lights/lie.hpp, lights/lie_direct.hpp) ----------------

#include <map>
#include <optional>
#include <set>
#include <vector>

#include <glint/lights/lie_direct.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "lie_hall.hpp"

namespace {

using LieAccel = MeshBvh<MollerTrumbore<float>, 8>;

/// The small hall: 30 point lights, 3 x 4 columns of 8 sides, 12 rows of 1 ring.
struct LieFixture {
    Scene<float> scene = lie_hall(30, 3, 8, 1);
    LieAccel accel{std::span<const TriangleVertices<float>>(scene.triangles)};
};

LieSettings lie_settings(int samples, bool early_blockers = true) {
    LieSettings s;
    s.early_blockers = early_blockers;
    s.samples = samples;
    s.depth = 5;
    return s;
}

/// Brute force: the outcome of light j's shadow ray at sp through the BVH (lie_visible,
/// lie_no_light or the first blocker), and its unshadowed contribution.
std::int32_t brute_outcome(const LieAccel& accel, const ShadingPoint<float>& sp, const LieLight<float>& l, Rgb<float>& c) {
    if (!lie_unshadowed(sp, l, c)) return lie_no_light;
    StoreHit<float> h;
    return accel.closest_hit(lie_shadow_ray(sp, l), h) ? std::int32_t(h.id) : lie_visible;
}

/// Calls fn(sp) at the surface point of each construction ray index in [first, last).
template <class F>
void for_sample_points(const LieFixture& f, std::uint64_t first, std::uint64_t last, F&& fn) {
    const Halton<float> h(2);
    for (std::uint64_t i = first; i < last; ++i) {
        std::optional<SurfaceBrdf<float>> brdf;
        ShadingPoint<float> sp;
        if (lie_camera_point(f.scene, f.accel, lie_sample_ray(f.scene.camera, h, i, 1.0f), brdf, sp)) fn(sp);
    }
}

/// The state machine replayed naively on the construction's samples: per (cell, light), whether
/// a sample saw it, whether one was blocked (after that, unless `early`), and those blockers.
struct Replayed {
    bool seen = false, blocked_after = false;
    std::set<std::uint32_t> blockers;
};

std::map<std::pair<std::uint32_t, std::uint32_t>, Replayed> replay(const LieFixture& f, const Lie<float>& lie, int samples,
                                                                  bool early = true) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, Replayed> r;
    for_sample_points(f, 1, std::uint64_t(samples) + 1, [&](const ShadingPoint<float>& sp) {
        const std::uint32_t c = lie.locate(sp.x);
        REQUIRE(c != LieOctree<float>::none);  // every sample's cell exists
        for (std::uint32_t j = 0; j < lie.lights().size(); ++j) {
            Rgb<float> v;
            const std::int32_t o = brute_outcome(f.accel, sp, lie.lights()[j], v);
            Replayed& e = r[{c, j}];
            if (o == lie_visible) e.seen = true;
            if (o >= 0 && (e.seen || early)) {
                e.blocked_after = true;
                e.blockers.insert(std::uint32_t(o));
            }
        }
    });
    return r;
}

const LieEntry* find_entry(const Lie<float>& lie, std::uint32_t c, std::uint32_t j) {
    for (const LieEntry& e : lie.entries(c))
        if (e.light == j) return &e;
    return nullptr;
}

/// Whether the LIE's state of light j in its cell is right for a point whose brute-force outcome
/// is o: absent and not visible, unoccluded and not blocked, partial and visible or blocked by a
/// listed triangle.
bool state_right(const Lie<float>& lie, const LieEntry* e, std::int32_t o) {
    if (o == lie_no_light) return true;
    if (!e) return o != lie_visible;
    if (e->state == LieState::unoccluded) return o == lie_visible;
    if (lie.settings().variant == LieVariant::three_state) return true;  // an ordinary shadow ray
    const auto ids = lie.blocker_triangles(*e);
    return o == lie_visible || std::find(ids.begin(), ids.end(), std::uint32_t(o)) != ids.end();
}

}  // namespace

TEST_CASE("LIE states are the state machine's on the construction samples, and every sampled point agrees") {
    const LieFixture f;
    const int n = 6000;
    for (const bool early : {true, false}) {
        CAPTURE(early);
        const Lie<float> lie(f.scene, f.accel, lie_settings(n, early));
        const auto r = replay(f, lie, n, early);
        std::size_t partial = 0;
        for (std::uint32_t c = 0; c < lie.cells().size(); ++c)
            for (std::uint32_t j = 0; j < lie.lights().size(); ++j) {
                const auto it = r.find({c, j});
                const Replayed e = it == r.end() ? Replayed{} : it->second;
                const LieEntry* le = find_entry(lie, c, j);
                // absent iff no sample of the cell saw the light; partial iff one was also blocked
                CHECK((le != nullptr) == e.seen);
                if (!le) continue;
                CHECK((le->state == LieState::partial) == e.blocked_after);
                const auto ids = lie.blocker_triangles(*le);
                CHECK(std::set<std::uint32_t>(ids.begin(), ids.end()) == e.blockers);
                CHECK(ids.size() == e.blockers.size());  // no blocker twice
                partial += le->state == LieState::partial;
            }
        CHECK(partial > 0);  // the fixture exercises blocker lists
        // At the sampled points: an absent light is occluded at every one; with early blockers
        // kept (§3.1's definition), an unoccluded light is visible at every one.
        std::size_t checked = 0, unoccluded_blocked = 0;
        for_sample_points(f, 1, n + 1, [&](const ShadingPoint<float>& sp) {
            const std::uint32_t c = lie.locate(sp.x);
            for (std::uint32_t j = 0; j < lie.lights().size(); ++j) {
                Rgb<float> v;
                const std::int32_t o = brute_outcome(f.accel, sp, lie.lights()[j], v);
                const LieEntry* e = find_entry(lie, c, j);
                if (!e) CHECK(o != lie_visible);
                else if (e->state == LieState::unoccluded) unoccluded_blocked += o >= 0;
                checked += o != lie_no_light;
            }
        });
        CHECK(checked > 50000);
        if (early) CHECK(unoccluded_blocked == 0);
        MESSAGE("early blockers " << early << ": " << unoccluded_blocked << " sampled (point, light) pairs blocked but unoccluded");
    }
}

TEST_CASE("LIE on fresh points: wrong only where no sample found the region (the stated bias), and shrinking with samples") {
    const LieFixture f;
    double rate[2];
    const int ns[2] = {1500, 6000};
    for (int k = 0; k < 2; ++k) {
        const Lie<float> lie(f.scene, f.accel, lie_settings(ns[k]));
        const auto r = replay(f, lie, ns[k]);
        std::size_t pairs = 0, wrong = 0;
        for_sample_points(f, 100001, 104001, [&](const ShadingPoint<float>& sp) {
            const std::uint32_t c = lie.locate(sp.x);
            if (c == LieOctree<float>::none) return;  // a cell no sample reached: plain shadow rays, exact
            for (std::uint32_t j = 0; j < lie.lights().size(); ++j) {
                Rgb<float> v;
                const std::int32_t o = brute_outcome(f.accel, sp, lie.lights()[j], v);
                if (o == lie_no_light) continue;
                ++pairs;
                const LieEntry* e = find_entry(lie, c, j);
                if (state_right(lie, e, o)) continue;
                ++wrong;
                // Explained by the bias: a visible point of a light no sample saw, or a blocker
                // no sample of the cell found.
                const auto it = r.find({c, j});
                const Replayed rep = it == r.end() ? Replayed{} : it->second;
                if (o == lie_visible) CHECK(!rep.seen);
                else CHECK(rep.blockers.count(std::uint32_t(o)) == 0);
            }
        });
        rate[k] = double(wrong) / double(pairs);
        MESSAGE("LIE with " << ns[k] << " samples: " << wrong << " of " << pairs << " fresh (point, light) pairs wrong ("
                            << 100 * rate[k] << "%)");
    }
    CHECK(rate[1] < rate[0]);  // Fernandez 2004, 4.8: unsampled regions shrink as (1 - s)^t
}

TEST_CASE("LIE shading through blockers is exactly the shadow-ray result wherever the states are right") {
    const LieFixture f;
    for (const auto variant : {LieVariant::blocker_lists, LieVariant::three_state}) {
        LieSettings s = lie_settings(6000);
        s.variant = variant;
        const LieDirect<float> lie(f.scene, f.accel, s, false);
        std::size_t right = 0, points = 0, blocker_rays = 0;
        for_sample_points(f, 200001, 203001, [&](const ShadingPoint<float>& sp) {
            RayQueries<LieAccel> q(f.accel);
            const auto shaded = lie.shade(sp, q);
            const auto brute = lie.shadow_rays(sp, q);
            const std::uint32_t c = lie.lie().locate(sp.x);
            bool all_right = true;
            for (std::uint32_t j = 0; j < lie.lie().lights().size() && c != LieOctree<float>::none; ++j) {
                Rgb<float> v;
                all_right &= state_right(lie.lie(), find_entry(lie.lie(), c, j), brute_outcome(f.accel, sp, lie.lie().lights()[j], v));
            }
            ++points;
            blocker_rays += shaded.cost.blocker_rays;
            if (!all_right) return;
            ++right;
            for (int b = 0; b < 3; ++b) CHECK(shaded.L[b] == brute.L[b]);  // bit for bit: same lights, same order
        });
        CAPTURE(int(variant));
        MESSAGE("variant " << int(variant) << ": every light's state right at " << right << " of " << points << " fresh points");
        CHECK(right > 1000);  // the exact comparison ran on many points
        CHECK((blocker_rays > 0) == (variant == LieVariant::blocker_lists));
    }
}

TEST_CASE("LIE masking drops less than 2% of the cell's minimum total at every sampled point") {
    const LieFixture f;
    const int n = 6000;
    const LieDirect<float> lie(f.scene, f.accel, lie_settings(n), true);
    const LieDirect<float> full(f.scene, f.accel, lie_settings(n), false);
    std::size_t masked_cells = 0, fresh = 0, fresh_over = 0;
    for (std::uint32_t c = 0; c < lie.lie().cells().size(); ++c) masked_cells += lie.lie().cell(c).masked > 0;
    CHECK(masked_cells > 0);
    auto dropped_at = [&](const ShadingPoint<float>& sp, float& total) {
        RayQueries<LieAccel> q(f.accel);
        total = full.shadow_rays(sp, q).L.luminance();
        float dropped = 0;
        for (const LieEntry& e : lie.lie().entries(lie.lie().locate(sp.x))) {
            Rgb<float> v;
            if (!e.masked) continue;
            if (brute_outcome(f.accel, sp, lie.lie().lights()[e.light], v) == lie_visible) dropped += v.luminance();
        }
        return dropped;
    };
    for_sample_points(f, 1, n + 1, [&](const ShadingPoint<float>& sp) {
        float total;
        const float dropped = dropped_at(sp, total);
        const auto& cell = lie.lie().cell(lie.lie().locate(sp.x));
        CHECK(cell.min_total <= total * (1 + 1e-5f));
        CHECK(dropped <= 0.02f * cell.min_total * (1 + 1e-5f));
    });
    for_sample_points(f, 300001, 302001, [&](const ShadingPoint<float>& sp) {
        if (lie.lie().locate(sp.x) == LieOctree<float>::none) return;
        float total;
        const float dropped = dropped_at(sp, total);
        ++fresh;
        fresh_over += dropped > 0.02f * total;
    });
    MESSAGE("masking: " << masked_cells << " of " << lie.lie().cells().size() << " cells drop lights; on fresh points "
                        << fresh_over << " of " << fresh << " lose more than 2% (unsampled points are not bounded)");
}

TEST_CASE("the LIE octree and states are the same for any thread count, fixed and adaptive") {
    const LieFixture f;
    for (const auto sub : {LieSubdivision::fixed, LieSubdivision::adaptive}) {
        LieSettings s = lie_settings(5000);
        s.subdivision = sub;
        s.blocker_threshold = 2;
        s.threads = 1;
        const Lie<float> a(f.scene, f.accel, s);
        s.threads = 3;
        const Lie<float> b(f.scene, f.accel, s);
        REQUIRE(a.octree().nodes().size() == b.octree().nodes().size());
        for (std::size_t i = 0; i < a.octree().nodes().size(); ++i) {
            CHECK(a.octree().nodes()[i].first_child == b.octree().nodes()[i].first_child);
            CHECK(a.octree().nodes()[i].cell == b.octree().nodes()[i].cell);
        }
        REQUIRE(a.all_entries().size() == b.all_entries().size());
        for (std::size_t i = 0; i < a.all_entries().size(); ++i) {
            CHECK(a.all_entries()[i].light == b.all_entries()[i].light);
            CHECK(a.all_entries()[i].state == b.all_entries()[i].state);
        }
        CHECK(a.all_blocker_triangles() == b.all_blocker_triangles());
        if (sub == LieSubdivision::adaptive) {
            // A list longer than the threshold only where the cell could not split further.
            std::size_t deep = 0;
            for (const auto& nd : a.octree().nodes()) {
                if (nd.cell == LieOctree<float>::none) continue;
                deep = std::max<std::size_t>(deep, nd.depth);
                for (const LieEntry& e : a.entries(nd.cell))
                    if (e.blocker_count > 2) CHECK(nd.depth == s.max_depth);
            }
            CHECK(deep > 1);
        }
    }
}

TEST_CASE("LIE settings are checked before any work, naming the value") {
    const LieFixture f;
    LieSettings s;
    s.depth = -1;
    CHECK_THROWS_WITH_AS(Lie<float>(f.scene, f.accel, s), doctest::Contains("depth must be in [0, 20], got -1"), Error);
    s = LieSettings{};
    s.samples = 0;
    CHECK_THROWS_WITH_AS(Lie<float>(f.scene, f.accel, s), doctest::Contains("samples must be >= 1, got 0"), Error);
    s = LieSettings{};
    s.blocker_threshold = 0;
    CHECK_THROWS_WITH_AS(Lie<float>(f.scene, f.accel, s), doctest::Contains("blocker_threshold"), Error);
}

TEST_CASE("LIE with area lights (as points on them) and spot lights: exact where the states are right") {
    Scene<float> scene = builtin_scene<float>("cornell");
    const AABB<float> b = [&] {
        AABB<float> a;
        for (const auto& t : scene.triangles)
            for (const auto& v : t) a.extend(v);
        return a;
    }();
    const Vec3<float> top(b.center().x, b.hi.y - 0.05f * b.extent().y, b.center().z);
    scene.point_lights.push_back(PointLight<float>::spot(top, Vec3<float>(0.2f, -1, 0.1f), Rgb<float>(3), 0.5f, 0.3f));
    scene.point_lights.push_back(PointLight<float>::oriented(top, Vec3<float>(0, -1, 0), Rgb<float>(1)));
    const LieAccel accel{std::span<const TriangleVertices<float>>(scene.triangles)};
    LieSettings s = lie_settings(4000);
    s.area_samples = 4;
    const LieDirect<float> lie(scene, accel, s, false);
    CHECK(lie.lie().lights().size() == scene.point_lights.size() + 4 * scene.area_lights.size());
    const Halton<float> h(2);
    std::size_t right = 0, points = 0;
    for (std::uint64_t i = 50001; i < 52001; ++i) {
        std::optional<SurfaceBrdf<float>> brdf;
        ShadingPoint<float> sp;
        if (!lie_camera_point(scene, accel, lie_sample_ray(scene.camera, h, i, 1.0f), brdf, sp)) continue;
        RayQueries<LieAccel> q(accel);
        const auto shaded = lie.shade(sp, q);
        const auto brute = lie.shadow_rays(sp, q);
        const std::uint32_t c = lie.lie().locate(sp.x);
        bool all_right = c != LieOctree<float>::none;
        for (std::uint32_t j = 0; all_right && j < lie.lie().lights().size(); ++j) {
            Rgb<float> v;
            all_right = state_right(lie.lie(), find_entry(lie.lie(), c, j), brute_outcome(accel, sp, lie.lie().lights()[j], v));
        }
        ++points;
        if (!all_right) continue;
        ++right;
        for (int k = 0; k < 3; ++k) CHECK(shaded.L[k] == brute.L[k]);
    }
    MESSAGE("cornell with spots and area points: every state right at " << right << " of " << points << " fresh points");
    CHECK(right > points / 2);  // the exact comparison ran on most points
    // Area-light emission after a vertex the LIE shaded is in the estimate already.
    StoreHit<float> light_hit;
    for (std::uint32_t t = 0; t < scene.triangles.size(); ++t)
        if (scene.light_of[t] >= 0) light_hit.id = t;
    CHECK(lie.emission_weight(Arrival<float>{true, 1.0f}, Ray<float>{}, light_hit) == 0.0f);
    CHECK(lie.emission_weight(Arrival<float>{}, Ray<float>{}, light_hit) == 1.0f);
}

// ---- The light tree's compact bounds (CompactLightBounds, lights/importance_pair.hpp) -------

namespace {

/// The importance bound as written term by term from Conty Estevez and Kulla 2018's eq. (the
/// angles of the bounding sphere's cone by their sines and cosines): the oracle that
/// CompactLightBounds' rearranged evaluation (shared square roots, sin theta_b = r / d) must
/// reproduce.
double importance_oracle(const LightBounds<float>& b, const Vec3<double>& x, const Vec3<double>& n) {
    if (!(b.phi > 0)) return 0;
    const Vec3<double> lo(b.box.lo), hi(b.box.hi), c = (lo + hi) * 0.5, d = x - c;
    const double r2 = glm::dot(hi - lo, hi - lo) * 0.25, d2 = glm::dot(d, d);
    const double theta_b = d2 > r2 ? std::asin(std::sqrt(r2 / d2)) : pi<double>;
    const Vec3<double> wi = d / std::sqrt(d2);
    const double theta_w = std::acos(std::clamp(glm::dot(Vec3<double>(b.w), wi), -1.0, 1.0));
    const double theta_o = std::acos(double(b.cos_theta_o)), theta_e = std::acos(double(b.cos_theta_e));
    const double theta_p = std::max(0.0, std::max(0.0, theta_w - theta_o) - theta_b);
    if (theta_p >= theta_e) return 0;
    const double theta_i = std::acos(std::clamp(-glm::dot(wi, n), -1.0, 1.0));
    return double(b.phi) * std::cos(theta_p) / std::max(d2, r2) * std::max(0.0, std::cos(std::max(0.0, theta_i - theta_b)));
}

}  // namespace

TEST_CASE("light tree: CompactLightBounds' importance and importance_pair are the bound's formula at every node of the hall's and the kitchen's trees") {
    RandomSampler<float> rng(11);
    for (const char* name : {"hall", "kitchen"}) {
        CAPTURE(name);
        const Scene<float> s = builtin_scene<float>(name);
        const LightTree<float> tree(scene_light_bounds(s));
        double worst = 0, worst_pair = 0;
        int positive = 0, zero = 0;
        for (int k = 0; k < 200; ++k) {
            // Points in the scene's box (outside and inside clusters' spheres), random normals.
            const Vec3<float> x(-26.0f + 52.0f * rng.get_1d(), 6.0f * rng.get_1d(), -12.0f + 24.0f * rng.get_1d());
            const Vec3<float> n = square_to_uniform_sphere(rng.get_2d());
            for (const auto& node : tree.nodes()) {
                const double fast = CompactLightBounds<float>(node.bounds).importance(x, n);
                const double exact = importance_oracle(node.bounds, Vec3<double>(x), Vec3<double>(n));
                // Float evaluation of cosines near a cone's edge: 1e-4 relative of the scale
                // phi / d^2 (the cos factors are <= 1), measured worst about 1e-6.
                const double scale = double(node.bounds.phi) / std::max(double(glm::dot(x - node.bounds.box.center(), x - node.bounds.box.center())), 1e-6);
                worst = std::max(worst, std::abs(fast - exact) / scale);
                (exact > 0 ? positive : zero) += 1;
            }
            // The pairs a descent evaluates together (SSE lanes for float on x86).
            for (std::size_t i = 0; i < tree.nodes().size(); ++i) {
                const auto& node = tree.nodes()[i];
                if (node.second < 0) continue;
                const auto& b0 = tree.nodes()[i + 1].bounds;
                const auto& b1 = tree.nodes()[std::size_t(node.second)].bounds;
                const auto pair = importance_pair(CompactLightBounds<float>(b0), CompactLightBounds<float>(b1), x, n);
                for (std::size_t side = 0; side < 2; ++side) {
                    const auto& bk = side ? b1 : b0;
                    const double exact = importance_oracle(bk, Vec3<double>(x), Vec3<double>(n));
                    const Vec3<float> dk = x - bk.box.center();
                    const double scale = double(bk.phi) / std::max(double(glm::dot(dk, dk)), 1e-6);
                    worst_pair = std::max(worst_pair, std::abs(double(pair[side]) - exact) / scale);
                }
            }
        }
        CAPTURE(worst);
        CAPTURE(worst_pair);
        CHECK(worst < 1e-4);
        CHECK(worst_pair < 1e-4);
        CHECK(positive > 1000);  // both outcomes occur often: lit and unlit nodes
        CHECK(zero > 1000);
    }
}
