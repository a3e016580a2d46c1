// Tests for glint/vpl: the VPL integrator agrees with the path tracer on Lambertian scenes
// (area and point lights) within standard errors measured with fixed seeds; clamping the
// geometry term darkens the image; gathering is exact for one VPL; images do not depend on
// the thread count; the fixed-point gather at primary_points equals the Renderer's image;
// light animation with path reuse: the frame weights sum to 1 and each
// frame's image mean agrees with an independent VPL render.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/path_tracer.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/vpl/integrator.hpp>
#include <glint/vpl/light_animation.hpp>
#include <glint/vpl/light_path_maps.hpp>
#include <glint/vpl/scenes.hpp>

using namespace glint;

namespace {

using Accel = MeshBvh<MollerTrumbore<float>, 8>;
/// The classic (albedo) roulette of the shooting walks.
glint::Roulette<float, 3> classic() { return glint::Roulette<float, 3>::classic(); }

/// The Cornell box with its area light replaced by a point light below the ceiling.
Scene<float> point_box() {
    return with_point_light(builtin_scene<float>("cornell"), Vec3<float>(0.1f, 1.7f, 0.2f), Rgb<float>(4.0f, 3.5f, 3.0f));
}

/// Means of the four image quadrants, per band (12 numbers).
std::vector<double> quadrant_means(const Image<Rgb<float>>& img) {
    std::vector<double> m(12, 0.0);
    const double n = double(img.size()) / 4;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const int q = (y * 2 / img.height) * 2 + x * 2 / img.width;
            for (int c = 0; c < 3; ++c) m[std::size_t(q * 3 + c)] += img.at(x, y)[std::size_t(c)] / n;
        }
    return m;
}

/// The path tracer's quadrant means and their standard errors (pixel centres, independent
/// pixels: the variance of a quadrant mean is the sum of its pixels' variances / n^2).
template <bool Points>
void path_traced(const Scene<float>& s, const Accel& accel, int size, int spp, std::vector<double>& mean,
                 std::vector<double>& se) {
    RenderSettings st;
    st.width = st.height = size;
    st.spp = spp;
    st.threads = 2;
    st.pixel_jitter = false;
    const PathTracer<Accel, RandomSampler<float>, MisDirect<float>> pt(s, accel, {.roulette = classic()});
    const RenderResult r = render_image(s, st, pt, RandomSampler<float>(7));
    mean = quadrant_means(r.image);
    const std::vector<double> var = quadrant_means(r.variance);  // mean pixel variance of the mean
    se.resize(12);
    const double n = double(r.image.size()) / 4;
    for (std::size_t i = 0; i < 12; ++i) se[i] = std::sqrt(var[i] / n);
}

/// Quadrant means of `runs` independent VPL renders (seeds 1..runs): their mean and
/// standard error (sample standard deviation / sqrt(runs)).
void vpl_runs(const Scene<float>& s, const Accel& accel, const RenderSettings& image, VplSettings st, int runs,
              std::vector<double>& mean, std::vector<double>& se) {
    std::vector<double> sum(12, 0.0), sum2(12, 0.0);
    const ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    for (int k = 0; k < runs; ++k) {
        st.seed = std::uint64_t(k + 1);
        const auto q = quadrant_means(render_vpl(s, accel, classic(), vis, image, st).image);
        for (std::size_t i = 0; i < 12; ++i) sum[i] += q[i], sum2[i] += q[i] * q[i];
    }
    mean.resize(12);
    se.resize(12);
    for (std::size_t i = 0; i < 12; ++i) {
        mean[i] = sum[i] / runs;
        se[i] = std::sqrt(std::max(0.0, (sum2[i] - runs * mean[i] * mean[i]) / (runs - 1)) / runs);
    }
}

void check_agreement(const std::vector<double>& a, const std::vector<double>& sa, const std::vector<double>& b,
                     const std::vector<double>& sb) {
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double z = (a[i] - b[i]) / std::sqrt(sa[i] * sa[i] + sb[i] * sb[i]);
        CAPTURE(i);
        CAPTURE(a[i]);
        CAPTURE(b[i]);
        CHECK(std::abs(z) < 4.0);
    }
}

/// size x size pixels, one camera ray through each pixel's centre.
RenderSettings centres(int size, int threads) {
    RenderSettings image;
    image.width = image.height = size;
    image.threads = threads;
    image.spp = 1;
    image.pixel_jitter = false;
    return image;
}

VplSettings with_walks(std::size_t walks) {
    VplSettings st;
    st.vpl_walks = walks;
    return st;
}

/// 32 VPL renders of 64 walks against a path-traced 256 spp image, 16 x 16 pixels.
template <bool Points>
void agreement_with_path_tracer(const Scene<float>& s) {
    const Accel accel(s.triangles);
    std::vector<double> pm, ps, vm, vs;
    path_traced<Points>(s, accel, 16, 256, pm, ps);
    vpl_runs(s, accel, centres(16, 2), with_walks(64), 32, vm, vs);
    check_agreement(vm, vs, pm, ps);
}

}  // namespace

TEST_CASE("exact: one visible VPL over a Lambertian floor gives f_x dPhi f_y cos cos / r^2") {
    Scene<float> s;
    const auto m = s.add_material(Material<float>::lambertian(Rgb<float>(0.5f)));
    s.add_quad(Vec3<float>(-1, 0, 1), Vec3<float>(1, 0, 1), Vec3<float>(1, 0, -1), Vec3<float>(-1, 0, -1), m);
    const Accel accel(s.triangles);
    PixelPoint<float> p;
    p.x = Vec3<float>(0.2f, 0, 0);
    p.n = Vec3<float>(0, 1, 0);
    p.wo = safe_normalize(Vec3<float>(0, 1, 1));
    p.weight = Rgb<float>(1);
    p.hit = true;
    const Vec3<float> y(0, 1, 0);
    const std::vector<Vpl<float>> vpls{{y, safe_normalize(Vec3<float>(1, -1, 0)), Rgb<float>(2, 1, 0.5f), Rgb<float>(0.8f)}};
    ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    const Rgb<float> L = gather_point(s, p, std::span<const Vpl<float>>(vpls), vis, 0.0f);
    const Vec3<float> d = y - p.x;
    const double r2 = glm::dot(d, d), cx = 1 / std::sqrt(r2), cy = glm::dot(safe_normalize(Vec3<float>(-1, 1, 0)), d) / std::sqrt(r2);
    for (std::size_t c = 0; c < 3; ++c)
        CHECK(L[c] == doctest::Approx(vpls[0].power[c] * 0.8 / M_PI * 0.5 / M_PI * cx * cy / r2).epsilon(1e-5));
    // Clamped at a distance beyond |x - y|: the squared distance becomes d_min^2.
    const Rgb<float> Lc = gather_point(s, p, std::span<const Vpl<float>>(vpls), vis, 4.0f);
    CHECK(Lc[0] == doctest::Approx(L[0] * r2 / 4.0).epsilon(1e-5));
}

namespace {

/// ShadowRayVisibility with its batch test hidden: a shadow ray at a time.
struct OneLightAtATime {
    ShadowRayVisibility<Accel> vis;
    void set_point(const Vec3<float>& x, const Vec3<float>& n) { vis.set_point(x, n); }
    bool visible(const Vec3<float>& y) const { return vis.visible(y); }
};

}  // namespace

TEST_CASE("VPL gather: shadow rays to a point's VPLs as one stream (MeshBvh's packets) sum what one ray at a time sums") {
    for (const Scene<float>& s : {builtin_scene<float>("cornell"), builtin_scene<float>("cornell-caustics"), point_box()}) {
        const Accel accel(s.triangles);
        RenderSettings image;
        image.width = image.height = 24;
        const auto points = primary_points(s, accel, image, VplSettings{});
        const auto vpls = shoot_scene_vpls(s, accel, classic(), 200, 5);
        const ShadowRayVisibility<Accel> batched(accel, 1e-4f);
        static_assert(BatchVisibilityPolicy<ShadowRayVisibility<Accel>, float>);
        static_assert(!BatchVisibilityPolicy<OneLightAtATime, float>);
        const std::span<const PixelPoint<float>> pts(points);
        const std::span<const Vpl<float>> vs(vpls);
        const auto streamed = gather_image(s, pts, vs, batched, 0.0, 2);
        const auto single = gather_image(s, pts, vs, OneLightAtATime{batched}, 0.0, 2);
        CAPTURE(s.name);
        REQUIRE(vpls.size() > 64);  // several blocks of the gather
        CHECK(streamed == single);
        int lit = 0;
        for (const Rgb<float>& L : streamed) lit += L.max() > 0.0f;
        CHECK(lit > int(points.size()) / 2);
    }
}

TEST_CASE("stress: bad settings and lightless scenes throw naming the value") {
    VplSettings st;
    st.min_distance = -1;
    CHECK_THROWS_WITH_AS(st.validate(), doctest::Contains("min_distance -1"), Error);
    st = VplSettings{};
    st.max_specular = -2;
    CHECK_THROWS_WITH_AS(st.validate(), doctest::Contains("max_specular -2"), Error);
    Scene<float> s;
    const auto m = s.add_material(Material<float>::lambertian(Rgb<float>(0.5f)));
    s.add_quad(Vec3<float>(-1, 0, 1), Vec3<float>(1, 0, 1), Vec3<float>(1, 0, -1), Vec3<float>(-1, 0, -1), m);
    CHECK_THROWS_WITH_AS(EmitterSet<float>{s}, doctest::Contains("no light"), Error);
    const Accel accel(s.triangles);
    s.point_lights.push_back({Vec3<float>(0, 1, 0), Rgb<float>(1)});
    CHECK_THROWS_WITH_AS(shoot_scene_vpls(s, accel, classic(), 0, 1), doctest::Contains("got 0"), Error);
}

TEST_CASE("agreement: VPL image equals the path tracer's on the Cornell box (area light) within standard errors") {
    agreement_with_path_tracer<false>(builtin_scene<float>("cornell"));
}

TEST_CASE("agreement: VPL image equals the path tracer's with a point light within standard errors") {
    agreement_with_path_tracer<true>(point_box());
}

TEST_CASE("agreement: clamping the geometry term only darkens; its bias is negative beyond its standard error") {
    const Scene<float> s = builtin_scene<float>("cornell");
    const Accel accel(s.triangles);
    const ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    const RenderSettings image = centres(16, 2);
    VplSettings st = with_walks(64);
    st.direct = false;
    double sum = 0, sum2 = 0, level = 0;
    const int runs = 16;
    for (int k = 0; k < runs; ++k) {
        st.seed = std::uint64_t(k + 1);
        st.min_distance = 0;
        const VplResult a = render_vpl(s, accel, classic(), vis, image, st);
        st.min_distance = 0.3;
        const VplResult b = render_vpl(s, accel, classic(), vis, image, st);
        double diff = 0;
        bool never_brighter = true;
        for (std::size_t i = 0; i < a.image.size(); ++i)
            for (std::size_t c = 0; c < 3; ++c) {
                never_brighter &= b.image.pixels[i][c] <= a.image.pixels[i][c];
                diff += double(b.image.pixels[i][c]) - double(a.image.pixels[i][c]);
            }
        CHECK(never_brighter);
        diff /= double(a.image.size() * 3);
        sum += diff, sum2 += diff * diff;
        for (const auto& p : a.image.pixels) level += (double(p[0]) + p[1] + p[2]) / double(3 * a.image.size() * runs);
    }
    const double mean = sum / runs, se = std::sqrt((sum2 - runs * mean * mean) / (runs - 1) / runs);
    MESSAGE("clamp 0.3: indirect image mean changes by ", mean / level * 100, "% (standard error ", se / level * 100, "%)");
    CHECK(mean < -3 * se);
}

TEST_CASE("exact: the VPL image does not depend on the thread count") {
    const Scene<float> s = builtin_scene<float>("cornell");
    const Accel accel(s.triangles);
    const ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    const VplSettings st = with_walks(16);
    const VplResult a = render_vpl(s, accel, classic(), vis, centres(12, 1), st);
    const VplResult b = render_vpl(s, accel, classic(), vis, centres(12, 3), st);
    CHECK(a.image.pixels == b.image.pixels);
    CHECK(a.vpls > 16);
}

TEST_CASE("exact: gathering at primary_points gives the Renderer's image, through a dielectric block") {
    // The Cornell box with its blocks made of glass: camera rays reach diffuse points through
    // Fresnel choices drawn from each pixel's sampler stream, which both passes must share.
    Scene<float> s = builtin_scene<float>("cornell");
    const auto glass = s.add_material(Material<float>::dielectric(1.5f));
    for (std::size_t i = 10; i + 2 < s.triangles.size(); ++i) s.material_of[i] = glass;
    const Accel accel(s.triangles);
    const ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    VplSettings st = with_walks(32);
    st.direct = false;
    st.min_distance = 0.1;
    st.seed = 9;
    const RenderSettings image = centres(24, 2);
    const auto vpls = shoot_scene_vpls(s, accel, classic(), st.vpl_walks, st.seed);
    const VplResult r = render_vpls(s, accel, std::span<const Vpl<float>>(vpls), vis, image, st);
    const auto points = primary_points(s, accel, image, st);
    const auto g = gather_image(s, std::span<const PixelPoint<float>>(points), std::span<const Vpl<float>>(vpls), vis,
                                st.min_distance, 2);
    REQUIRE(g.size() == r.image.pixels.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < g.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) differ += g[i][c] != r.image.pixels[i][c];
    CHECK(r.rays > g.size() + 50);  // one ray per pixel, and more through the glass
    CHECK(differ == 0);
}

TEST_CASE("exact: balance weights sum to 1, keep zeros, and reject bad densities") {
    Pcg32 rng(3, 4);
    for (int t = 0; t < 100; ++t) {
        std::vector<double> q(1 + t % 7), a(q.size());
        for (auto& v : q) v = rng.uniform<double>() < 0.3 ? 0.0 : std::exp(8 * rng.uniform<double>() - 4);
        q[0] = 0.5;  // the own frame always sees its own first hit
        balance_weights(std::span<const double>(q), std::span<double>(a));
        double sum = 0;
        for (std::size_t j = 0; j < q.size(); ++j) {
            sum += a[j];
            CHECK((q[j] == 0) == (a[j] == 0));
        }
        CHECK(sum == doctest::Approx(1.0).epsilon(1e-12));
    }
    std::vector<double> q{1.0, -1.0}, a(2), b(3);
    CHECK_THROWS_WITH_AS(balance_weights(std::span<const double>(q), std::span<double>(a)), doctest::Contains("density 1 is -1"), Error);
    CHECK_THROWS_WITH_AS(balance_weights(std::span<const double>(q), std::span<double>(b)), doctest::Contains("2 densities but 3"), Error);
}

namespace {

std::vector<Vec3<float>> track(std::size_t frames) {
    return light_track(Vec3<float>(-0.7f, 1.7f, 0.2f), Vec3<float>(0.7f, 1.7f, 0.2f), frames);
}

double image_mean(const std::vector<Rgb<float>>& img, std::size_t c) {
    double m = 0;
    for (const auto& p : img) m += p[c] / double(img.size());
    return m;
}

}  // namespace

TEST_CASE("exact: every path's frame weights sum to 1; paths are reused across frames") {
    const Scene<float> s = point_box();
    const Accel accel(s.triangles);
    const auto path = track(6);
    AnimationOptions opt;
    opt.paths_per_frame = 8;
    const LightAnimation<float> a = shoot_light_animation(s, accel, classic(), std::span<const Vec3<float>>(path),
                                                          Rgb<float>(1), opt);
    std::size_t reused = 0, occluded = 0;
    for (std::size_t p = 0; p < a.paths.size(); ++p) {
        double sum = 0;
        for (std::size_t i = 0; i < a.frames(); ++i) {
            const float w = a.weight(p, i, 0, a.frames() - 1);
            sum += w;
            reused += w > 0 && i != a.paths[p].frame;
            occluded += a.paths[p].reusable && w == 0;
        }
        CAPTURE(p);
        CHECK(sum == doctest::Approx(1.0).epsilon(1e-6));
    }
    CHECK(reused > a.paths.size());  // most paths serve several frames
    CHECK(occluded > 0);             // and the boxes hide some first hits from some frames
}

TEST_CASE("agreement: each frame of the path-reuse animation equals independent VPL renders within standard errors") {
    const Scene<float> s = point_box();
    const Accel accel(s.triangles);
    const ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    const std::size_t F = 4, runs = 48;
    const auto path = track(F);
    const RenderSettings image = centres(8, 2);
    VplSettings st = with_walks(32);  // independent renders: 32 walks per frame
    st.direct = false;
    // Both sides clamp the geometry term alike: the clamped sum is still linear in the VPLs'
    // powers, so both estimate the same quantity, with far less variance than unclamped.
    st.min_distance = 0.25;
    const auto points = primary_points(s, accel, image, st);
    // Per frame and band: sums over runs of the image mean, for reuse (off-line, on-line with
    // a window of 2 frames) and for independent VPL renders.
    std::vector<double> sum(3 * F * 3, 0.0), sum2(3 * F * 3, 0.0);
    for (std::size_t r = 0; r < runs; ++r) {
        AnimationOptions opt;
        opt.paths_per_frame = 8;
        opt.seed = 100 + r;
        LightAnimation<float> a = shoot_light_animation(s, accel, classic(), std::span<const Vec3<float>>(path),
                                                        Rgb<float>(4.0f, 3.5f, 3.0f), opt);
        render_path_images(a, s, std::span<const PixelPoint<float>>(points), vis, st.min_distance, image.threads);
        for (std::size_t f = 0; f < F; ++f) {
            Scene<float> sf = s;
            sf.point_lights[0].position = path[f];
            st.seed = 1000 + r * F + f;
            const VplResult v = render_vpl(sf, accel, classic(), vis, image, st);
            std::vector<Rgb<float>> indep(v.indirect.pixels.begin(), v.indirect.pixels.end());
            const std::vector<Rgb<float>> img[3] = {a.frame_image(f), a.frame_image(f, 2), indep};
            for (std::size_t m = 0; m < 3; ++m)
                for (std::size_t c = 0; c < 3; ++c) {
                    const double x = image_mean(img[m], c);
                    sum[(m * F + f) * 3 + c] += x;
                    sum2[(m * F + f) * 3 + c] += x * x;
                }
        }
    }
    auto stat = [&](std::size_t k, double& mean, double& var_of_mean) {
        mean = sum[k] / double(runs);
        var_of_mean = std::max(0.0, sum2[k] / double(runs) - mean * mean) / double(runs - 1);
    };
    for (std::size_t k = 0; k < F * 3; ++k) {
        double mi, vi;
        stat(2 * F * 3 + k, mi, vi);
        for (std::size_t m = 0; m < 2; ++m) {
            double mr, vr;
            stat(m * F * 3 + k, mr, vr);
            CAPTURE(m);
            CAPTURE(k);
            CAPTURE(mr);
            CAPTURE(mi);
            CHECK(std::abs(mr - mi) < 4 * std::sqrt(vr + vi));
        }
    }
}

TEST_CASE("exact: the reference grid holds each triangle's lattice points, and each point's stencil is itself") {
    const Scene<float> s = point_box();
    for (const int g : {1, 2, 5}) {
        const ReferenceGrid<float> grid(s, g);
        CHECK(grid.per_triangle() == std::size_t((g + 1) * (g + 2) / 2));
        CHECK(grid.size() == s.triangles.size() * grid.per_triangle());
        const auto& v = s.triangles[3];
        for (int j = 0; j <= g; ++j)
            for (int i = 0; i + j <= g; ++i) {
                CAPTURE(g);
                CAPTURE(i);
                CAPTURE(j);
                const float u = float(i) / float(g), w = float(j) / float(g);
                const std::size_t r = grid.index(3, i, j);
                CHECK(grid.tri[r] == 3);
                CHECK(glm::length(grid.x[r] - (v[0] * (1 - u - w) + v[1] * u + v[2] * w)) < 1e-6f);
                const ReferenceGrid<float>::Stencil st = grid.stencil(3, u, w);
                for (int k = 0; k < 3; ++k) {
                    if (st.index[k] == r) {
                        CHECK(std::abs(st.weight[k] - 1.0f) < 1e-6f);
                    } else {
                        CHECK(std::abs(st.weight[k]) < 1e-6f);
                    }
                }
            }
    }
    CHECK_THROWS_WITH_AS(ReferenceGrid<float>(s, 0), doctest::Contains("grid 0"), Error);
    CHECK_THROWS_WITH_AS(ReferenceGrid<float>(s, 4, 0.6f), doctest::Contains("inset 0.6"), Error);
}

TEST_CASE("exact: interpolating a linear function of position recorded at the lattice reproduces it everywhere") {
    const Scene<float> s = point_box();
    // Three linear functions of position, one per band.
    const auto f = [](const Vec3<float>& x) {
        return Rgb<float>(0.5f + 0.3f * x.x - 0.2f * x.y + 0.1f * x.z, 1.0f - 0.4f * x.x + 0.25f * x.z, 0.7f * x.y + 0.2f);
    };
    // Inset 0: interpolation, weights in [0, 1]; inset 0.1: extrapolation near the edges.
    for (const float inset : {0.0f, 0.1f})
        for (const int g : {1, 3, 8}) {
            const ReferenceGrid<float> grid(s, g, inset);
            std::vector<Rgb<float>> values(grid.size());
            for (std::size_t r = 0; r < grid.size(); ++r) values[r] = f(grid.x[r]);
            Pcg32 rng(11, std::uint64_t(g));
            for (int n = 0; n < 400; ++n) {
                const std::uint32_t t = std::uint32_t(rng.uniform<float>() * float(s.triangles.size())) % std::uint32_t(s.triangles.size());
                float u = rng.uniform<float>(), v = rng.uniform<float>();
                if (u + v > 1) u = 1 - u, v = 1 - v;
                if (n % 10 == 0) v = 1 - u;  // on the edge opposite vertex 0
                if (n % 10 == 1) u = 0;      // on an edge through vertex 0
                const auto& p = s.triangles[t];
                const Rgb<float> want = f(p[0] * (1 - u - v) + p[1] * u + p[2] * v);
                const Rgb<float> got = grid.interpolate(std::span<const Rgb<float>>(values), t, u, v);
                const ReferenceGrid<float>::Stencil st = grid.stencil(t, u, v);
                CAPTURE(inset);
                CAPTURE(g);
                CAPTURE(t);
                CAPTURE(u);
                CAPTURE(v);
                CHECK(std::abs(st.weight[0] + st.weight[1] + st.weight[2] - 1.0f) < 1e-5f);
                for (int k = 0; k < 3; ++k) CHECK((inset > 0 || st.weight[k] > -1e-6f));
                for (std::size_t c = 0; c < 3; ++c) CHECK(std::abs(got[c] - want[c]) < 4e-6f * (1.0f + std::abs(want[c])));
            }
        }
    // Through the renderer's pixel points: their (u, v) follow the same vertex convention.
    const Accel accel(s.triangles);
    const ReferenceGrid<float> grid(s, 4);
    std::vector<Rgb<float>> values(grid.size());
    for (std::size_t r = 0; r < grid.size(); ++r) values[r] = f(grid.x[r]);
    const LightPathMap<float> map{grid, {}, {}, {}, {}};
    const auto points = primary_points(s, accel, centres(16, 1), VplSettings{});
    const auto img = light_path_map_image(map, s, std::span<const PixelPoint<float>>(points), std::span<const Rgb<float>>(values));
    int hits = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (!points[i].hit) continue;
        ++hits;
        const Rgb<float> want = points[i].weight * s.materials[points[i].material].kd * f(points[i].x) / pi<float>;
        CAPTURE(i);
        for (std::size_t c = 0; c < 3; ++c) CHECK(std::abs(img[i][c] - want[c]) < 1e-5f * (1.0f + std::abs(want[c])));
    }
    CHECK(hits > 200);
}

TEST_CASE("agreement: the light path map's indirect irradiance equals VPL gathering at the reference points") {
    const Scene<float> s = point_box();
    const Accel accel(s.triangles);
    const ShadowRayVisibility<Accel> vis(accel, 1e-4f);
    const int runs = 24;
    // Per band: image means over the reference points of the LPM and of independent VPL
    // renders gathered at the same points (both clamped alike: linear in the VPLs' powers).
    std::vector<double> sum(6, 0.0), sum2(6, 0.0);
    for (int r = 0; r < runs; ++r) {
        LightPathMapOptions opt;
        opt.entry_points = 256;
        opt.branches = 2;
        opt.grid = 2;
        opt.min_distance = 0.25;
        opt.threads = 2;
        opt.seed = std::uint64_t(50 + r);
        const LightPathMap<float> map = build_light_path_map(s, accel, classic(), vis, opt);
        const auto e = entry_irradiance(map, s, accel, 1, 1);
        const auto lpm = reference_irradiance(map, std::span<const Rgb<float>>(e));
        std::vector<PixelPoint<float>> points(map.grid.size());
        for (std::size_t i = 0; i < points.size(); ++i) {
            points[i].x = map.grid.x[i];
            points[i].n = points[i].wo = map.ref_normal[i];
            points[i].material = s.material_of[map.grid.tri[i]];
            points[i].weight = Rgb<float>(1);
            points[i].hit = true;
        }
        VplSettings st = with_walks(128);
        st.min_distance = 0.25;
        st.seed = std::uint64_t(900 + r);
        const auto vpls = shoot_scene_vpls(s, accel, classic(), st.vpl_walks, st.seed);
        const auto vpl = gather_image(s, std::span<const PixelPoint<float>>(points), std::span<const Vpl<float>>(vpls), vis,
                                    st.min_distance, 2);
        for (std::size_t c = 0; c < 3; ++c) {
            double a = 0, b = 0;
            for (std::size_t i = 0; i < points.size(); ++i) {
                const double kd = s.materials[points[i].material].kd[c];
                a += kd / M_PI * lpm[i][c] / double(points.size());
                b += vpl[i][c] / double(points.size());
            }
            sum[c] += a, sum2[c] += a * a, sum[3 + c] += b, sum2[3 + c] += b * b;
        }
    }
    for (std::size_t c = 0; c < 3; ++c) {
        const double ma = sum[c] / runs, mb = sum[3 + c] / runs;
        const double va = (sum2[c] / runs - ma * ma) / (runs - 1), vb = (sum2[3 + c] / runs - mb * mb) / (runs - 1);
        CAPTURE(c);
        CAPTURE(ma);
        CAPTURE(mb);
        CHECK(std::abs(ma - mb) < 4 * std::sqrt(va + vb));
    }
}
