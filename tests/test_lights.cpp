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
