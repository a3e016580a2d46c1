// Tests for glint/lights: the point emitters' profiles integrate to the power they state, and
// bad lights are rejected by index.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>
#include <ctime>
#include <limits>

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
#include "glint_instances.hpp"  // render_named for AnyAccel, compiled once (instances/)

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
    std::vector<SurfaceBrdf<float>> brdfs;
    std::vector<ShadingPoint<float>> points;
    ShadingPoints(const Scene<float>& s, const DefaultAccel& accel, int nx, int ny) {
        brdfs.reserve(std::size_t(nx * ny));
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                const Ray<float> ray = s.camera.ray((float(i) + 0.5f) / float(nx), (float(j) + 0.5f) / float(ny), 1.0f);
                StoreHit<float> hit;
                if (!accel.closest_hit(ray, hit)) continue;
                ShadingPoint<float> sp = shading_point(s, hit, s.normal(hit.id), ray.direction);
                brdfs.emplace_back(s.materials[s.material_of[hit.id]], sp.frame.to_local(-ray.direction));
                sp.brdf = &brdfs.back();
                points.push_back(sp);
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
        const RenderResult r = render_named(s, any_accel_view(accel), o);
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

#include <glint/lights/scenes.hpp>

namespace {

using LieAccel = MeshBvh<MollerTrumbore<float>, 8>;

/// The LIE hall (lights/scenes.hpp) small: 6 x 6 point lights, 25 pillars of 8 sides, 1 ring.
struct LieFixture {
    Scene<float> scene = lie_hall_scene<float>(8, 1, 6);
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
    if (!point_light_unshadowed(l.light, sp, c)) return lie_no_light;
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

// ---- Light cluster trees and dense cuts (lights/light_points.hpp, cluster_tree.hpp, cuts.hpp,
// cut_direct.hpp): each accepted node's true error is within its bound on every pixel of a
// small scene, the tree is the same on every build and builds in O(n log n), a cut with
// threshold 0 is the exact sum, and the VPL gather through a cut meets the same checks.

#include <chrono>
#include <numeric>
#include <utility>
#include <vector>

#include <glint/core/random.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/lights/cluster_tree.hpp>
#include <glint/lights/cut_direct.hpp>
#include <glint/lights/cuts.hpp>
#include <glint/lights/light_points.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/vpl/integrator.hpp>
#include "counted_visibility.hpp"

namespace {

using CutAccel = MeshBvh<MollerTrumbore<float>, 8>;

/// n lights of every kind at random in a 10-unit cube, fixed seed.
std::vector<PointLight<float>> random_lights(std::size_t n, std::uint64_t seed) {
    Pcg32 rng(seed, 3);
    std::vector<PointLight<float>> out;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3<float> p(rng.uniform<float>() * 10, rng.uniform<float>() * 10, rng.uniform<float>() * 10);
        const Vec3<float> a = square_to_uniform_sphere(Vec2<float>(rng.uniform<float>(), rng.uniform<float>()));
        const Rgb<float> I(rng.uniform<float>() + 0.1f, rng.uniform<float>() + 0.1f, rng.uniform<float>() + 0.1f);
        if (i % 3 == 0) out.push_back(PointLight<float>::isotropic(p, I));
        else if (i % 3 == 1) out.push_back(PointLight<float>::oriented(p, a, I));
        else out.push_back(PointLight<float>::spot(p, a, I, 0.7f, 0.4f));
    }
    return out;
}

/// The glossy Cornell box's light as 128 oriented points, 64 walks' VPLs as cosine points, and
/// isotropic and spot lights inside the box: every kind of light and both lobes.
struct CutFixture {
    Scene<float> scene = builtin_scene<float>("cornell-glossy");
    CutAccel accel{scene.triangles};
    std::vector<Vpl<float>> vpls = shoot_scene_vpls(scene, accel, Roulette<float, 3>::classic(), 64, 5);
    std::vector<PointLight<float>> lights;
    CutFixture() {
        lights = scene_light_points(scene, LightPointOptions<float>{.total = 128});
        const auto v = vpl_light_points<float>(std::span<const Vpl<float>>(vpls));
        lights.insert(lights.end(), v.begin(), v.end());
        for (int i = 0; i < 8; ++i) {
            const Vec3<float> p(-0.8f + 0.2f * float(i), 1.5f, -0.5f + 0.1f * float(i));
            lights.push_back(i % 2 ? PointLight<float>::isotropic(p, Rgb<float>(0.3f))
                                   : PointLight<float>::spot(p, Vec3<float>(0, -1, 0), Rgb<float>(0.5f, 0.4f, 0.3f), 0.8f, 0.5f));
        }
    }
};

/// Pixel-centre camera rays of a size x size image.
RenderSettings pixel_centres(int size) {
    RenderSettings image;
    image.width = image.height = size;
    image.spp = 1;
    image.pixel_jitter = false;
    return image;
}

/// Calls visit(receiver, visible) at the first diffuse or glossy point of every pixel centre of
/// a size x size image of f's scene; visible(light) traces the light's shadow ray.
template <class Visit>
void for_each_receiver(const CutFixture& f, int size, Visit&& visit) {
    const auto points = primary_points(f.scene, f.accel, pixel_centres(size), VplSettings{});
    ShadowRayVisibility<CutAccel> vis(f.accel, 1e-4f);
    const auto visible = [&](const PointLight<float>& l) { return vis.visible(l.position); };
    for (const auto& p : points) {
        if (!p.hit) continue;
        const Frame<float> frame = Frame<float>::from_normal(p.n);
        const SurfaceBrdf<float> brdf(f.scene.materials[p.material], frame.to_local(p.wo));
        vis.set_point(p.x, p.n);
        visit(CutReceiver<float>{p.x, p.n, frame, &brdf, 0.0f}, visible);
    }
}

/// The lights below node k.
void subtree_lights(const LightClusterTree<float>& t, std::uint32_t k, std::vector<std::uint32_t>& out) {
    const auto& n = t.node(k);
    if (n.leaf()) return out.push_back(n.rep);
    subtree_lights(t, n.left, out);
    subtree_lights(t, n.right, out);
}

bool same_tree(const LightClusterTree<float>& a, const LightClusterTree<float>& b) {
    if (a.nodes().size() != b.nodes().size()) return false;
    for (std::size_t i = 0; i < a.nodes().size(); ++i) {
        const auto &x = a.nodes()[i], &y = b.nodes()[i];
        if (x.left != y.left || x.right != y.right || x.rep != y.rep || x.box.lo != y.box.lo || x.box.hi != y.box.hi ||
            x.theta_o != y.theta_o || !(x.intensity == y.intensity))
            return false;
    }
    return true;
}

}  // namespace

namespace {

/// The orientation group of light l as ClusterGrouping::by_orientation defines it (the cube
/// face its axis points to; isotropic lights a seventh group), computed here independently.
int orientation_group(const PointLight<float>& l) {
    if (l.kind == PointLightKind::isotropic) return 6;
    int k = 0;
    for (int a = 1; a < 3; ++a)
        if (std::abs(l.axis[a]) > std::abs(l.axis[k])) k = a;
    return 2 * k + (l.axis[k] < 0 ? 1 : 0);
}

}  // namespace

TEST_CASE("cluster tree: grouped by orientation, only the merges of the groups' roots mix groups") {
    const LightClusterTree<float> t(random_lights(700, 16), ClusterGrouping::by_orientation);
    REQUIRE(t.nodes().size() == 1399);
    std::vector<std::uint32_t> below;
    int mixed = 0;
    for (std::uint32_t k = 0; k < t.nodes().size(); ++k) {
        below.clear();
        subtree_lights(t, k, below);
        const int g = orientation_group(t.lights()[below[0]]);
        mixed += std::any_of(below.begin(), below.end(), [&](std::uint32_t i) { return orientation_group(t.lights()[i]) != g; });
    }
    CHECK(mixed == 6);  // seven groups (six cube faces, the isotropic lights) joined by six merges
    const LightClusterTree<float> spatial(random_lights(700, 16));
    CHECK(!same_tree(t, spatial));
}

namespace {

/// Every node sums its children, holds their boxes, cones and centroids, and takes a child's representative.
void check_tree_structure(ClusterGrouping grouping) {
    CAPTURE(int(grouping));
    const LightClusterTree<float> t(random_lights(500, 11), grouping);
    REQUIRE(t.nodes().size() == 999);
    std::vector<int> parents(t.nodes().size(), 0);
    for (std::uint32_t k = 0; k < t.nodes().size(); ++k) {
        const auto& n = t.node(k);
        if (n.leaf()) {
            CHECK(n.box.contains(t.lights()[n.rep].position));
            CHECK(n.centroid == t.lights()[n.rep].position);  // a leaf's light is its approximation
            CHECK(n.mean_axis == t.lights()[n.rep].axis);
            continue;
        }
        // The centroid, a weighted mean of at most 500 positions in float, lies in the box up to
        // 500 roundings of the box's largest coordinate.
        float size = 0;
        for (int c = 0; c < 3; ++c) size = std::max({size, std::abs(n.box.lo[c]), std::abs(n.box.hi[c])});
        const float tol = 500 * std::numeric_limits<float>::epsilon() * size;
        for (int c = 0; c < 3; ++c) CHECK((n.centroid[c] >= n.box.lo[c] - tol && n.centroid[c] <= n.box.hi[c] + tol));
        CHECK(glm::length(n.mean_axis) == doctest::Approx(1.0f).epsilon(4 * std::numeric_limits<float>::epsilon()));
        const auto &l = t.node(n.left), &r = t.node(n.right);
        ++parents[n.left], ++parents[n.right];
        CHECK((n.rep == l.rep || n.rep == r.rep));
        for (int c = 0; c < 3; ++c) CHECK(n.intensity[std::size_t(c)] == doctest::Approx(l.intensity[std::size_t(c)] + r.intensity[std::size_t(c)]));
        CHECK(n.box.contains(l.box.lo));
        CHECK(n.box.contains(r.box.hi));
    }
    for (std::uint32_t k = 0; k < 500; ++k) {  // every light's axis lies in every ancestor's cone
        const auto& l = t.lights()[k];
        if (l.kind == PointLightKind::isotropic) continue;
        for (std::uint32_t a = 0; a < t.nodes().size(); ++a) {
            std::vector<std::uint32_t> below;
            if (k % 50 != 0) break;  // a sample of the lights keeps this fast
            if (t.node(a).leaf()) continue;
            subtree_lights(t, a, below);
            if (std::find(below.begin(), below.end(), k) == below.end()) continue;
            const auto& n = t.node(a);
            CHECK(std::acos(std::clamp(glm::dot(n.axis, l.axis), -1.0f, 1.0f)) <= n.theta_o + 1e-4f);
        }
    }
    CHECK(parents[t.root()] == 0);
    CHECK(std::count(parents.begin(), parents.end(), 1) == 998);
}

}  // namespace

TEST_CASE("cluster tree: every node sums its children, holds their boxes, cones and centroids, and takes a child's representative") {
    check_tree_structure(ClusterGrouping::spatial);
    check_tree_structure(ClusterGrouping::by_orientation);
}

TEST_CASE("cluster tree: the same lights give the same tree on every build") {
    const auto lights = random_lights(3000, 12);
    const LightClusterTree<float> a(lights), b(lights);
    CHECK(same_tree(a, b));
    const LightClusterTree<float> c(random_lights(3000, 13));
    CHECK(!same_tree(a, c));  // the comparison can fail
}

namespace {

/// The CPU seconds this thread spends building a cluster tree over `lights` (the thread's own
/// clock: time slices given to other processes on a busy machine do not count).
double cluster_build_cpu_seconds(const std::vector<PointLight<float>>& lights) {
    timespec a{}, b{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a);
    const LightClusterTree<float> tree(lights);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &b);
    CHECK(tree.nodes().size() == 2 * lights.size() - 1);
    return double(b.tv_sec - a.tv_sec) + 1e-9 * double(b.tv_nsec - a.tv_nsec);
}

}  // namespace

TEST_CASE("cluster tree: building 10^4 lights costs far less than 100x building 10^3 (O(n log n), not O(n^2))") {
    const auto small = random_lights(1000, 14), large = random_lights(10000, 15);
    double t_small = 1e30, t_large = 1e30;
    for (int rep = 0; rep < 5; ++rep) {  // the fastest of five: a build that met no interruption
        t_small = std::min(t_small, cluster_build_cpu_seconds(small));
        t_large = std::min(t_large, cluster_build_cpu_seconds(large));
    }
    MESSAGE("build: 10^3 lights " << t_small * 1e3 << " ms, 10^4 lights " << t_large * 1e3 << " ms, ratio " << t_large / t_small);
    CHECK(t_large / t_small < 40.0);  // n log n predicts ~13, n^2 predicts 100
}

namespace {

/// On every pixel each accepted node's true error is within its bound, and within twice the threshold.
void check_cut_bounds(const CutFixture& f, ClusterGrouping grouping, CutError estimate) {
    CAPTURE(int(grouping));
    CAPTURE(int(estimate));
    const LightClusterTree<float> tree(f.lights, grouping);
    std::vector<CutRecord<float>> trace;
    std::vector<std::uint32_t> below;
    int checked = 0, clustered = 0;
    for_each_receiver(f, 16, [&](const CutReceiver<float>& r, const auto& visible) {
        trace.clear();
        const auto res = evaluate_cut(tree, r, CutSettings{.error = estimate}, visible, &trace);
        CHECK(res.shadow_rays <= res.nodes);
        CHECK(res.nodes <= 300);
        for (const auto& rec : trace) {
            below.clear();
            subtree_lights(tree, rec.node, below);
            Rgb<float> exact(0), exact_rep_v(0);  // each light's own visibility; the representative's
            for (std::uint32_t i : below) {
                const auto& l = tree.lights()[i];
                const Rgb<float> c = light_factor(l, r) * l.intensity;
                if (c.max() > 0 && visible(l)) exact += c;
                if (rec.visible) exact_rep_v += c;
            }
            for (std::size_t c = 0; c < 3; ++c) {
                const float tol = 1e-4f * (rec.bound[c] + exact[c]) + 1e-12f;
                CHECK(std::abs(exact[c] - rec.estimate[c]) <= rec.bound[c] + tol);
                CHECK(std::abs(exact_rep_v[c] - rec.estimate[c]) <= rec.bound[c] + tol);
            }
            if (rec.by_threshold && below.size() > 1) {
                Rgb<float> diff;
                for (std::size_t c = 0; c < 3; ++c) diff[c] = std::abs(exact[c] - rec.estimate[c]);
                CHECK(diff.luminance() <= 2 * rec.allowed * 1.0001f + 1e-12f);
                ++clustered;
            }
            ++checked;
        }
    });
    MESSAGE(checked << " accepted nodes checked, " << clustered << " of them clusters accepted by the threshold");
    CHECK(clustered > 1000);  // the check is about clusters, not leaves
}

}  // namespace

TEST_CASE("cuts: on every pixel each accepted node's true error is within its bound, and within twice the threshold") {
    const CutFixture f;
    for (const CutError estimate : {CutError::bound, CutError::fernandez}) {
        check_cut_bounds(f, ClusterGrouping::spatial, estimate);
        check_cut_bounds(f, ClusterGrouping::by_orientation, estimate);
    }
}

TEST_CASE("cuts: with threshold 0 and no size limit the cut is the exact sum over the lights") {
    const CutFixture f;
    const LightClusterTree<float> tree(f.lights);
    for_each_receiver(f, 8, [&](const CutReceiver<float>& r, const auto& visible) {
        const auto cut = evaluate_cut(tree, r, CutSettings{.threshold = 0, .max_nodes = 0}, visible);
        Rgb<float> exact(0);
        for (const auto& l : tree.lights()) {
            const Rgb<float> c = light_factor(l, r) * l.intensity;
            if (c.max() > 0 && visible(l)) exact += c;
        }
        for (std::size_t c = 0; c < 3; ++c) CHECK(cut.L[c] == doctest::Approx(exact[c]).epsilon(1e-4));
    });
}

TEST_CASE("VPL gather through a cut: threshold 0 equals gathering every VPL; the default cut traces far fewer rays, alike on any thread count") {
    const CutFixture f;
    const auto points = primary_points(f.scene, f.accel, pixel_centres(12), VplSettings{});
    const std::span<const PixelPoint<float>> pts(points);
    const auto vpls = shoot_scene_vpls(f.scene, f.accel, Roulette<float, 3>::classic(), 1024, 6);
    const std::span<const Vpl<float>> vs(vpls);
    std::uint64_t rays = 0;
    const CountedVisibility<ShadowRayVisibility<CutAccel>> vis{ShadowRayVisibility<CutAccel>(f.accel, 1e-4f), &rays};
    const auto all = gather_image(f.scene, pts, VplLights<float>(vs), vis, 0.05, 1);
    const std::uint64_t rays_all = std::exchange(rays, 0);
    const auto exact = gather_image(f.scene, pts, VplLights<float>(vs, VplGather::cuts, {.threshold = 0, .max_nodes = 0}), vis, 0.05, 1);
    rays = 0;
    const auto cut = gather_image(f.scene, pts, VplLights<float>(vs, VplGather::cuts), vis, 0.05, 1);
    const VplLights<float> spatial(vs, VplGather::cuts, {}, ClusterGrouping::spatial);
    const auto cut_spatial = gather_image(f.scene, pts, spatial, ShadowRayVisibility<CutAccel>(f.accel, 1e-4f), 0.05, 1);
    const VplLights<float> cuts(vs, VplGather::cuts);  // one tree, gathered on 1 and on 3 threads
    const ShadowRayVisibility<CutAccel> plain(f.accel, 1e-4f);
    CHECK(gather_image(f.scene, pts, cuts, plain, 0.05, 1) == gather_image(f.scene, pts, cuts, plain, 0.05, 3));
    MESSAGE("shadow rays: every VPL " << rays_all << ", the default cut " << rays);
    CHECK(rays * 4 < rays_all);
    double e = 0, e_spatial = 0;
    for (std::size_t i = 0; i < all.size(); ++i) {
        for (std::size_t c = 0; c < 3; ++c) CHECK(exact[i][c] == doctest::Approx(all[i][c]).epsilon(1e-4));
        const double L = all[i].luminance();
        e += L > 0 ? std::min(std::abs(cut[i].luminance() - L) / L, 1.0) : 0.0;
        e_spatial += L > 0 ? std::min(std::abs(cut_spatial[i].luminance() - L) / L, 1.0) : 0.0;
    }
    e /= double(all.size());
    e_spatial /= double(all.size());
    // The per-node bounds do not bound E (a sum of many nodes' errors): measured, 0.019 here.
    MESSAGE("E (Fernandez 2004 eq. 4.3) of the default cut over " << vpls.size() << " VPLs: " << e
                                                                  << "; with Fernandez 2004's spatial tree: " << e_spatial);
    CHECK(e < e_spatial);  // the VPLs of a wall share its normal: grouped, their clusters' bounds are tight
}

TEST_CASE("CutDirect: counts area-light emission only where it did not light the vertex; bad knobs are rejected") {
    const Scene<float> s = builtin_scene<float>("cornell");
    const CutDirect<float> d(s, PathTracerSettings<float>{});
    CHECK(d.tree().lights().size() == 4096);
    StoreHit<float> hit;
    hit.id = std::uint32_t(std::find_if(s.light_of.begin(), s.light_of.end(), [](int l) { return l >= 0; }) - s.light_of.begin());
    const Ray<float> ray{Vec3<float>(0, 1, 0), Vec3<float>(0, 1, 0), 0.0f, 10.0f};
    CHECK(d.emission_weight(Arrival<float>{true, 1.0f}, ray, hit) == 0.0f);
    CHECK(d.emission_weight(Arrival<float>{}, ray, hit) == 1.0f);
    hit.id = 0;  // the floor: not a light
    CHECK(d.emission_weight(Arrival<float>{true, 1.0f}, ray, hit) == 1.0f);
    CHECK_THROWS_WITH_AS(CutDirect<float>(s, LightPointOptions<float>{}, CutSettings{.threshold = -1}),
                         doctest::Contains("threshold -1"), Error);
    CHECK_THROWS_WITH_AS(scene_light_points(s, LightPointOptions<float>{.spacing = -0.5f}), doctest::Contains("spacing -0.5"),
                         Error);
}

namespace {

/// Quadrant means (per channel) of a path-traced 12 x 12 image of `s` (pixel centres, 32 spp) with direct
/// lighting `direct`, and their standard errors from the pixels' variances.
template <class D>
void quadrants(const Scene<float>& s, const CutAccel& accel, const D& direct, std::vector<double>& mean,
               std::vector<double>& se) {
    RenderSettings st;
    st.width = st.height = 12;
    st.spp = 32;
    st.threads = 2;
    st.pixel_jitter = false;  // pixel centres: the noise is the walks', not the film's edges
    const PathTracer<CutAccel, RandomSampler<float>, D> pt(s, accel, direct, MisEnvironment<float>(s), PathTracerSettings<float>{});
    const RenderResult r = render_image(s, st, pt, RandomSampler<float>(9));
    mean.assign(12, 0.0);
    se.assign(12, 0.0);
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 12; ++x)
            for (std::size_t c = 0; c < 3; ++c) {
                const std::size_t q = std::size_t((y / 6) * 2 + x / 6) * 3 + c;
                mean[q] += r.image.at(x, y)[c] / 36.0;
                se[q] += r.variance.at(x, y)[c] / (36.0 * 36.0);
            }
    for (double& v : se) v = std::sqrt(v);
}

}  // namespace

TEST_CASE("CutDirect in the path tracer: exact over its points it agrees with MisDirect; the default cut's bias is under 2%") {
    const Scene<float> s = builtin_scene<float>("cornell");
    const CutAccel accel(s.triangles);
    const LightPointOptions<float> points{.point_lights = false, .total = 256};
    std::vector<double> mis, mis_se, exact, exact_se, cut, cut_se;
    quadrants(s, accel, MisDirect<float>(s, PathTracerSettings<float>{}), mis, mis_se);
    quadrants(s, accel, CutDirect<float>(s, points, CutSettings{.threshold = 0, .max_nodes = 0}), exact, exact_se);
    quadrants(s, accel, CutDirect<float>(s, points, CutSettings{}), cut, cut_se);
    for (std::size_t i = 0; i < 12; ++i) {
        CAPTURE(i);
        // 256 points split the light: their bias is below this image's noise.
        CHECK(std::abs(exact[i] - mis[i]) < 4 * std::sqrt(exact_se[i] * exact_se[i] + mis_se[i] * mis_se[i]));
        // CutDirect draws no random numbers: both cut renders follow the same walks, and
        // differ only by the cuts' errors at their vertices.
        CHECK(std::abs(cut[i] - exact[i]) < 0.02 * exact[i]);
        MESSAGE("quadrant/channel " << i << ": mis " << mis[i] << " +- " << mis_se[i] << ", exact cut " << exact[i]
                                    << ", default cut " << cut[i]);
    }
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

// ---------------------------------------------------------------------------------------------
// Sparse sampling (Fernandez 2004, §5.3-5.4): interpolation and reconstruction cuts.

#include <glint/lights/sparse_direct.hpp>

namespace {

using SparseAccel = MeshBvh<MollerTrumbore<float>, 8>;

/// The small LIE hall (36 point lights, pillars, screens and low walls) and its accelerator.
struct SparseFixture {
    Scene<float> scene = lambertian(lie_hall_scene<float>(8, 1, 6));
    SparseAccel accel{std::span<const TriangleVertices<float>>(scene.triangles)};

    /// The sparse methods shade Lambertian points (glossy ones take the dense cut): the glossy floor made diffuse.
    static Scene<float> lambertian(Scene<float> s) {
        for (auto& m : s.materials)
            if (m.kind == MaterialKind::glossy) m = Material<float>::lambertian(m.kd);
        return s;
    }
};

SparseSettings sparse_settings(SparseMode mode, int threads = 1) {
    SparseSettings s;
    s.mode = mode;
    s.samples = 1500;
    s.threads = threads;
    return s;
}

/// A primary hit of a pixel centre, its BRDF kept with it.
struct SparsePixel {
    std::optional<SurfaceBrdf<float>> brdf;
    ShadingPoint<float> sp;
    int x = 0, y = 0;
};

/// The diffuse hits of the pixel centres of a size x size view (square, as the samples').
std::vector<SparsePixel> sparse_pixels(const SparseFixture& f, int size) {
    std::vector<SparsePixel> out;
    out.reserve(std::size_t(size * size));
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            out.emplace_back();
            SparsePixel& p = out.back();
            p.x = x;
            p.y = y;
            const Ray<float> ray = f.scene.camera.ray((float(x) + 0.5f) / float(size), (float(y) + 0.5f) / float(size), 1.0f);
            if (!lie_camera_point(f.scene, f.accel, ray, p.brdf, p.sp)) out.pop_back();
        }
    return out;
}

/// The exact direct light at p over the tree's lights: every light its own shadow ray.
Rgb<float> sparse_exact(const SparseDirect<float>& d, const SparsePixel& p, RayQueries<SparseAccel>& q) {
    const CutReceiver<float> r{p.sp.x, p.sp.n, p.sp.frame, p.sp.brdf, 0.0f};
    return evaluate_cut(d.tree(), r, CutSettings{0.0, 0}, [&](const PointLight<float>& l) { return CutDirect<float>::visible(p.sp, l, q); }).L;
}

}  // namespace

TEST_CASE("sparse: reconstruction cuts with agreement 0 are the dense cut at every pixel; at 5% they interpolate nodes and save rays") {
    const SparseFixture f;
    const SparseDirect<float> recon(f.scene, f.accel, LightPointOptions<float>{}, sparse_settings(SparseMode::reconstruct));
    const SparseDirect<float> strict = recon.with(SparseMode::reconstruct, 0.0);
    RayQueries<SparseAccel> q(f.accel);
    long dense_rays = 0, recon_rays = 0, interpolated = 0, fallbacks = 0;
    const auto pixels = sparse_pixels(f, 32);
    REQUIRE(pixels.size() > 800);
    for (const SparsePixel& p : pixels) {
        const CutReceiver<float> r{p.sp.x, p.sp.n, p.sp.frame, p.sp.brdf, 0.0f};
        const CutResult<float> dense =
            evaluate_cut(recon.tree(), r, recon.settings().cut, [&](const PointLight<float>& l) { return CutDirect<float>::visible(p.sp, l, q); });
        const auto s = strict.shade(p.sp, q);
        CHECK(s.interpolated == 0);
        for (std::size_t c = 0; c < 3; ++c) CHECK(s.L[c] == dense.L[c]);
        CHECK(s.shadow_rays == dense.shadow_rays);
        const auto loose = recon.shade(p.sp, q);
        dense_rays += dense.shadow_rays;
        recon_rays += loose.shadow_rays;
        interpolated += loose.interpolated;
        fallbacks += loose.dense;
    }
    MESSAGE("shadow rays per pixel: dense " << double(dense_rays) / double(pixels.size()) << ", reconstruction "
                                            << double(recon_rays) / double(pixels.size()) << "; interpolated nodes per pixel "
                                            << double(interpolated) / double(pixels.size()) << "; dense fallbacks " << fallbacks);
    CHECK(fallbacks < long(pixels.size()) / 10);
    CHECK(interpolated > long(pixels.size()));
    CHECK(recon_rays < dense_rays);
}

TEST_CASE("sparse: interpolation returns a sample's own value there (k = 2), and is a normalized Epanechnikov average") {
    const SparseFixture f;
    SparseSettings s2 = sparse_settings(SparseMode::interpolate);
    s2.neighbours = 2;
    const SparseDirect<float> two(f.scene, f.accel, LightPointOptions<float>{}, s2);
    const SparseDirect<float> eight(f.scene, f.accel, LightPointOptions<float>{}, sparse_settings(SparseMode::interpolate));
    const SparseSamples<float>& S = eight.samples();
    REQUIRE(S.size() > 1000);
    std::vector<SampleNeighbour<float>> near;
    int checked = 0;
    for (std::size_t i = 0; i < S.size(); i += 7) {
        two.samples().nearest(S.position(i), S.normal(i), 2, near);
        REQUIRE(near.size() == 2);
        if (near[0].sample != i) continue;  // another sample at the very same point
        const Rgb<float> e = two.interpolate(near);
        for (std::size_t c = 0; c < 3; ++c) CHECK(e[c] == S.irradiance(i)[c]);
        S.nearest(S.position(i), S.normal(i), 8, near);
        if (near.size() < 8) continue;
        double sum = 0, lo = 1e30, hi = -1e30;
        double w = 0;
        const double dk2 = double(near.back().distance) * double(near.back().distance);
        for (std::size_t j = 0; j + 1 < near.size(); ++j) {
            const double p = (dk2 - double(near[j].distance) * double(near[j].distance)) / dk2;
            CHECK(p >= 0.0);
            CHECK(p <= 1.0);
            const Rgb<float>& E = S.irradiance(near[j].sample);
            sum += double(E[1]) * p;
            w += p;
            lo = std::min(lo, double(E[1]));
            hi = std::max(hi, double(E[1]));
        }
        const Rgb<float> e8 = eight.interpolate(near);
        CHECK(double(e8[1]) == doctest::Approx(sum / w).epsilon(1e-5));
        CHECK(double(e8[1]) >= lo * (1 - 1e-6));  // a convex combination: the weights are normalized
        CHECK(double(e8[1]) <= hi * (1 + 1e-6));
        ++checked;
    }
    CHECK(checked > 100);
}

namespace {

/// Eq. 4.3's per-pixel error min(|L - L_exact| / L_exact, 1) on luminance.
double sparse_error(const Rgb<float>& L, const Rgb<float>& exact) {
    const double e = exact.luminance(), d = std::abs(double(L.luminance()) - e);
    return e > 0 ? std::min(d / e, 1.0) : (d > 0 ? 1.0 : 0.0);
}

}  // namespace

TEST_CASE("sparse: interpolation's bias is at shadow edges (stated), where reconstruction cuts keep the error small") {
    const SparseFixture f;
    const SparseDirect<float> interp(f.scene, f.accel, LightPointOptions<float>{}, sparse_settings(SparseMode::interpolate));
    const SparseDirect<float> recon = interp.with(SparseMode::reconstruct, 0.05);
    RayQueries<SparseAccel> q(f.accel);
    const int size = 48;
    const auto pixels = sparse_pixels(f, size);
    // Each pixel's shadowed fraction (exact light / light without shadows); a pixel is at a
    // shadow edge when it differs from a 4-neighbour's by more than 0.05.
    std::vector<double> lit(std::size_t(size * size), -1);
    std::vector<Rgb<float>> exact(std::size_t(size * size));
    for (const SparsePixel& p : pixels) {
        const CutReceiver<float> r{p.sp.x, p.sp.n, p.sp.frame, p.sp.brdf, 0.0f};
        const double open = evaluate_cut(interp.tree(), r, CutSettings{0.0, 0}, [](const PointLight<float>&) { return true; }).L.luminance();
        const std::size_t i = std::size_t(p.y * size + p.x);
        exact[i] = sparse_exact(interp, p, q);
        lit[i] = open > 0 ? exact[i].luminance() / open : 1.0;
    }
    double err[2][3] = {}, count[2] = {};
    const SparseDirect<float> strict = interp.with(SparseMode::reconstruct, 0.0);
    for (const SparsePixel& p : pixels) {
        bool edge = false;
        const std::size_t i = std::size_t(p.y * size + p.x);
        for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
            const int x = p.x + dx, y = p.y + dy;
            if (x >= 0 && y >= 0 && x < size && y < size && lit[std::size_t(y * size + x)] >= 0)
                edge = edge || std::abs(lit[std::size_t(y * size + x)] - lit[i]) > 0.05;
        }
        err[edge][0] += sparse_error(interp.shade(p.sp, q).L, exact[i]);
        err[edge][1] += sparse_error(recon.shade(p.sp, q).L, exact[i]);
        err[edge][2] += sparse_error(strict.shade(p.sp, q).L, exact[i]);
        count[edge] += 1;
    }
    REQUIRE(count[0] > 300);
    REQUIRE(count[1] > 300);
    const double ie = err[1][0] / count[1], io = err[0][0] / count[0], re = err[1][1] / count[1], ro = err[0][1] / count[0];
    const double de = err[1][2] / count[1], d_o = err[0][2] / count[0];
    MESSAGE("E at shadow edges / elsewhere (" << count[1] << " / " << count[0] << " pixels): interpolation " << ie << " / " << io
                                             << ", reconstruction " << re << " / " << ro << ", dense " << de << " / " << d_o);
    CHECK(ie > io);        // the stated bias: interpolation blurs shadow edges, its error is largest there
    CHECK(ie > 4 * re);    // reconstruction cuts keep the edges (§5.3.2)
    CHECK(re < de + 0.01);  // and add under 1% to the dense cut's own error, at edges and elsewhere
    CHECK(ro < d_o + 0.01);
}

TEST_CASE("sparse: the samples and every pixel's light are the same for any construction thread count") {
    const SparseFixture f;
    const SparseDirect<float> one(f.scene, f.accel, LightPointOptions<float>{}, sparse_settings(SparseMode::reconstruct, 1));
    const SparseDirect<float> three(f.scene, f.accel, LightPointOptions<float>{}, sparse_settings(SparseMode::reconstruct, 3));
    const SparseSamples<float>&a = one.samples(), &b = three.samples();
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        CHECK(a.position(i) == b.position(i));
        CHECK(a.irradiance(i).luminance() == b.irradiance(i).luminance());
        CHECK(std::ranges::equal(a.values(i), b.values(i)));
        CHECK(std::ranges::equal(a.left(i), b.left(i)));
    }
    RayQueries<SparseAccel> q(f.accel);
    for (const SparsePixel& p : sparse_pixels(f, 16))
        for (const SparseMode m : {SparseMode::interpolate, SparseMode::reconstruct})
            CHECK(one.with(m, 0.05).shade(p.sp, q).L.luminance() == three.with(m, 0.05).shade(p.sp, q).L.luminance());
    MESSAGE("bytes per sample (" << a.size() << " samples): " << a.bytes_per_sample());
}

TEST_CASE("sparse: sample priorities (§5.4.3) keep the uniform samples, then favour large reconstruction cuts far from samples") {
    const SparseFixture f;
    SparseSettings half = sparse_settings(SparseMode::reconstruct), prio = sparse_settings(SparseMode::reconstruct);
    half.samples = 750;
    prio.priority = 0.5;  // 750 uniform and 750 prioritized of 3000 candidates
    const SparseDirect<float> uniform(f.scene, f.accel, LightPointOptions<float>{}, half);
    const SparseDirect<float> chosen(f.scene, f.accel, LightPointOptions<float>{}, prio);
    prio.threads = 3;
    const SparseDirect<float> chosen3(f.scene, f.accel, LightPointOptions<float>{}, prio);
    const SparseSamples<float>&U = uniform.samples(), &P = chosen.samples();
    REQUIRE(U.size() > 500);
    REQUIRE(P.size() == U.size() + 750);
    REQUIRE(chosen3.samples().size() == P.size());
    std::set<std::uint64_t> picked;
    for (std::size_t i = 0; i < P.size(); ++i) {
        CHECK(chosen3.samples().halton_index(i) == P.halton_index(i));  // any thread count
        if (i < U.size()) CHECK(P.position(i) == U.position(i));      // the uniform samples first
        else picked.insert(P.halton_index(i));
    }
    // Each candidate's priority under the uniform samples, as the placement computes it.
    RayQueries<SparseAccel> q(f.accel);
    const Halton<float> h(2);
    std::vector<std::pair<double, bool>> w;  // priority, picked
    for (std::uint64_t index = 751; index <= 750 + 3000; ++index) {
        std::optional<SurfaceBrdf<float>> brdf;
        ShadingPoint<float> sp;
        if (!lie_camera_point(f.scene, f.accel, lie_sample_ray(f.scene.camera, h, index, 1.0f), brdf, sp)) continue;
        std::vector<SampleNeighbour<float>> near;
        U.nearest(sp.x, sp.n, 1, near);
        const double d = near.empty() ? double(U.radius()) : double(near.front().distance);
        w.push_back({double(std::max(1, uniform.shade(sp, q).nodes)) * d, picked.count(index) > 0});
    }
    REQUIRE(w.size() > 2000);
    CHECK(std::ranges::count_if(w, [](const auto& c) { return c.second; }) == 750);  // only candidates are picked
    // Drawn in proportion to priority: the top quarter of the candidates' priorities holds far
    // more than a quarter of the picks. A pick that ignored priority (hypergeometric: mean 187.5
    // of 750, standard deviation about 10) would exceed 187.5 + 4 sd with probability < 1e-4.
    std::vector<double> sorted;
    for (const auto& c : w) sorted.push_back(c.first);
    std::ranges::sort(sorted);
    const double top = sorted[sorted.size() * 3 / 4];
    double top_picks = 0, picked_mean = 0, all_mean = 0;
    for (const auto& c : w) {
        top_picks += c.second && c.first >= top;
        picked_mean += c.second ? c.first / 750.0 : 0.0;
        all_mean += c.first / double(w.size());
    }
    const double sd = std::sqrt(750.0 * 0.25 * 0.75 * (1.0 - 750.0 / double(w.size())));
    MESSAGE("picks in the top quarter of priorities: " << top_picks << " of 750 (uniform: 187.5 +- " << sd
                                                       << "); mean priority picked " << picked_mean << ", all " << all_mean);
    CHECK(top_picks > 187.5 + 4.0 * sd);
    CHECK(picked_mean > all_mean);
}

TEST_CASE("sparse: secondary and glossy vertices take the dense cut; bad settings are rejected naming the value") {
    const SparseFixture f;
    SparseSettings s = sparse_settings(SparseMode::interpolate);
    s.samples = 200;
    const SparseDirect<float> d(f.scene, f.accel, LightPointOptions<float>{}, s);
    RayQueries<SparseAccel> q(f.accel);
    RandomSampler<float> sampler(1);
    const auto pixels = sparse_pixels(f, 8);
    REQUIRE(!pixels.empty());
    const ShadingPoint<float>& sp = pixels.front().sp;
    const CutReceiver<float> r{sp.x, sp.n, sp.frame, sp.brdf, 0.0f};
    const auto dense = evaluate_cut(d.tree(), r, s.cut, [&](const PointLight<float>& l) { return CutDirect<float>::visible(sp, l, q); });
    CHECK(d.estimate(sp, sampler, q, nullptr).luminance() == dense.L.luminance());  // no vertex record: not primary
    const SurfaceBrdf<float> glossy(Material<float>::glossy(Rgb<float>(0.4f), Rgb<float>(0.3f), 20.0f), Vec3<float>(0, 0, 1));
    ShadingPoint<float> gp = sp;
    gp.brdf = &glossy;
    CHECK(d.shade(gp, q).dense);
    Scene<float> dark = f.scene;  // no lights: no samples, no light, no crash
    dark.point_lights.clear();
    const SparseDirect<float> none(dark, f.accel, LightPointOptions<float>{}, s);
    CHECK(none.samples().size() == 0);
    CHECK(none.shade(sp, q).L.luminance() == 0.0f);
    const auto rejects = [&](auto&& edit, const char* value) {
        SparseSettings b = s;
        edit(b);
        CHECK_THROWS_WITH_AS(SparseDirect<float>(f.scene, f.accel, LightPointOptions<float>{}, b), doctest::Contains(value), Error);
    };
    rejects([](SparseSettings& b) { b.samples = 0; }, "samples 0");
    rejects([](SparseSettings& b) { b.neighbours = 1; }, "neighbours 1");
    rejects([](SparseSettings& b) { b.neighbours = 40; }, "neighbours 40");
    rejects([](SparseSettings& b) { b.agreement = -0.5; }, "agreement -0.5");
    rejects([](SparseSettings& b) { b.max_radius = 0; }, "max_radius 0");
    rejects([](SparseSettings& b) { b.cut.max_nodes = 0; }, "max_nodes 0");
    rejects([](SparseSettings& b) { b.cut.threshold = -1; }, "threshold -1");
    rejects([](SparseSettings& b) { b.priority = 1; }, "priority 1");
    rejects([](SparseSettings& b) { b.candidates = 0; }, "candidates 0");
}
