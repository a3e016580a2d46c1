// glint/tracer/path_tracer.hpp: the bundled reference path tracer, composed of policies.
//
// 000 section 1.3 (lines 200-735): the rendering equation L = Le + T L is estimated by random
// walks; at every diffuse or glossy vertex the direct illumination is estimated by a
// direct-lighting policy (next-event estimation), and the walk continues or stops by a
// Russian-roulette policy with a BRDF-selection estimator (000 sections 2.1-2.3 through
// glint::scatter). Policies:
//   Accel    anything with closest_hit(ray, StoreHit&) and any_hit(ray) (trees/, BruteForce);
//   Sampler  glint::Sampler (RandomSampler, HaltonSampler);
//   Roulette glint::RoulettePolicy (classic, spectral, radiance estimate);
//   Direct   BrdfOnlyDirect (no next-event estimation: emission is collected where paths hit
//            it), MisDirect (light sampling and BRDF sampling combined by the balance
//            heuristic, Veach and Guibas 1995; the BRDF sample is the walk's continuation ray,
//            so a vertex costs one closest-hit ray and one shadow ray per light sample),
//            CorrelatedDirect (000 section 3.2: multiple correlated
//            sampling of polygon lights, with the importance, correlated or combined
//            estimator chosen at run time so that the three are compared on equal code).
//   Env, Points  compile-time switches: a scene without an environment map or point lights
//            gets a tracer with no environment or point-light code on the path.
// Specular (mirror, dielectric) vertices are followed deterministically (Fresnel choice for
// dielectrics) and count emission on the next hit, as camera rays do.
//
// Rendering is multithreaded over 16x16 tiles with std::thread; every pixel sample draws from
// the sampler's stream for (x, y, sample index), so the image does not depend on the thread
// count or the order tiles are rendered in.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <span>
#include <thread>
#include <type_traits>
#include <vector>

#include <glint/core/image.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/sampling/correlated.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/brdf.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// Which estimator CorrelatedDirect returns (000 section 3.2): lambda = 0, lambda = 1, or
/// lambda estimated from the samples (eq. 3.3).
enum class DirectEstimator { importance, correlated, combined };

struct RenderSettings {
    int width = 256, height = 256;
    int spp = 16;
    /// Cap on a walk's vertices, far beyond where roulette stops walks (a grey furnace of
    /// albedo 0.99 continues past 1024 vertices with probability about 3e-5); walks that reach
    /// it are counted in RenderResult::capped_walks, since a cap truncates (biases) them.
    int max_depth = 1024;
    int light_samples = 1;       // per area light and vertex (CorrelatedDirect, MisDirect)
    int threads = 0;             // 0: std::thread::hardware_concurrency()
    BrdfSelection selection = BrdfSelection::mis;
    DirectEstimator estimator = DirectEstimator::combined;
    /// Combined estimator at the primary vertices: lambda from the statistics pooled over
    /// the (2r + 1)^2 pixel neighbourhood (000 section 3.1.1); -1 estimates it per vertex.
    int lambda_filter_radius = 1;
    bool progress = false;       // progress bar on stderr
    /// Camera rays through uniformly jittered points of each pixel (the pixel's area average,
    /// the default) or through its centre only. With centres, an image estimates the radiance
    /// along fixed rays, so that its error against a reference of the same rays is light
    /// transport's alone: comparisons of estimators (bench_convergence) are not diluted by
    /// the pixel-footprint noise at silhouettes and light edges that every method shares.
    bool pixel_jitter = true;
};

struct RenderResult {
    Image<Rgb<float>> image;     // mean radiance per pixel
    Image<Rgb<float>> variance;  // variance of that mean (sample variance / spp)
    Image<float> lambda;         // mean lambda of the primary vertices (CorrelatedDirect)
    double seconds = 0;
    std::uint64_t rays = 0;      // closest-hit plus shadow rays
    std::uint64_t paths = 0;     // camera paths (pixel samples)
    std::uint64_t capped_walks = 0;  // walks cut at RenderSettings::max_depth (biased)
};

/// What a walk counts as it goes: rays traced and walks cut by the depth cap.
struct PathCounters {
    std::uint64_t rays = 0;
    std::uint64_t capped = 0;
};

/// How emission found at the end of a ray is weighted, given the vertex the ray left: whole
/// (camera rays, specular bounces, no light sampling), or, where lights were also sampled
/// there, by the BRDF sample's balance-heuristic weight with `pdf` the BRDF-sampling density
/// of the ray's direction (MisDirect; CorrelatedDirect's area lights get weight 0, since its
/// light samples estimate their whole contribution).
template <Scalar T>
struct Arrival {
    bool lights_sampled = false;
    T pdf = T(0);
};

/// The per-vertex inputs of a direct-lighting policy.
template <Scalar T>
struct ShadingPoint {
    Vec3<T> x;          // position
    Vec3<T> err;        // bound on x's rounding error, per axis
    Vec3<T> n;          // normal on the side of the outgoing direction
    Frame<T> frame;     // local frame about n
    const SurfaceBrdf<T>* brdf;
};

/// Per-pixel sums of the primary vertices' correlated-sampling quantities, so that the
/// combined estimate f/p + lambda (J - g/p) can use a lambda pooled over neighbouring pixels
/// after all samples are taken (it is linear in lambda).
template <Scalar T>
struct PrimaryDirect {
    Rgb<T> used{T(0)};  // what radiance() added with the per-vertex lambda
    Rgb<T> a{T(0)};     // sum of mean f/p
    Rgb<T> b{T(0)};     // sum of J - mean g/p
    Rgb<T> fg{T(0)}, gg{T(0)};  // sums of the within-vertex co-moments
};

/// No next-event estimation: the walk collects emission wherever it hits it.
struct BrdfOnlyDirect {
    static constexpr const char* name = "brdf";
    static constexpr bool collects_emission = true;
};

/// Light sampling (area lights by power, then uniform area; the environment by its map) and
/// one BRDF sample, combined by the balance heuristic.
struct MisDirect {
    static constexpr const char* name = "mis";
    static constexpr bool collects_emission = false;
};

/// 000 section 3.2: per area light, K points uniform on the polygon; f = Le fr G V,
/// main part g = Le fr~ G (V dropped, fr~ = kd / pi) with J from the point-to-polygon form
/// factor (eq. 3.4); the estimator (importance, correlated, combined) is a run-time setting.
/// The environment, if any, is sampled as in MisDirect.
struct CorrelatedDirect {
    static constexpr const char* name = "correlated";
    static constexpr bool collects_emission = false;
};

template <class D>
concept DirectLighting = requires {
    { D::name } -> std::convertible_to<const char*>;
    { D::collects_emission } -> std::convertible_to<bool>;
};

template <RayAccelerator Accel, class S, class R, DirectLighting D, bool Env, bool Points, Scalar T = float>
    requires Sampler<S, T> && RoulettePolicy<R, T, 3>
class PathTracer {
public:
    PathTracer(const Scene<T>& scene, const Accel& accel, const R& roulette, const RenderSettings& settings)
        : scene_(scene), accel_(accel), roulette_(roulette), settings_(settings) {
        scene.validate();
        for (const auto& l : scene.area_lights) {
            lights_.emplace_back(std::span<const Vec3<T>>(l.vertices), l.emission);
            light_power_ += l.emission.luminance() * l.area;
            light_cdf_.push_back(light_power_);
        }
    }

    /// Renders with one sampler per thread, copied from `prototype`.
    RenderResult render(const S& prototype) const {
        const int w = settings_.width, h = settings_.height, spp = std::max(1, settings_.spp);
        RenderResult out{Image<Rgb<float>>(w, h), Image<Rgb<float>>(w, h), Image<float>(w, h), 0, 0};
        const int tile = 16, tx = (w + tile - 1) / tile, ty = (h + tile - 1) / tile, tiles = tx * ty;
        std::atomic<int> next{0}, done{0};
        std::atomic<std::uint64_t> rays{0}, capped{0};
        std::mutex progress_mutex;
        const auto start = std::chrono::steady_clock::now();
        const bool pool_lambda = std::is_same_v<D, CorrelatedDirect> && settings_.estimator == DirectEstimator::combined &&
                                 settings_.lambda_filter_radius >= 0 && !lights_.empty();
        std::vector<PrimaryDirect<T>> primaries(pool_lambda ? std::size_t(w) * std::size_t(h) : 0);
        auto worker = [&] {
            S sampler = prototype;
            PathCounters local;
            for (int t = next++; t < tiles; t = next++) {
                const int x0 = (t % tx) * tile, y0 = (t / tx) * tile;
                for (int y = y0; y < std::min(y0 + tile, h); ++y)
                    for (int x = x0; x < std::min(x0 + tile, w); ++x)
                        render_pixel(x, y, spp, sampler, out, local,
                                     pool_lambda ? &primaries[std::size_t(y) * std::size_t(w) + std::size_t(x)] : nullptr);
                const int d = ++done;
                if (settings_.progress) {
                    std::lock_guard lock(progress_mutex);
                    const int bar = 40 * d / tiles;
                    std::fprintf(stderr, "\r[%.*s%.*s] %3d%%", bar, "########################################",
                                 40 - bar, "                                        ", 100 * d / tiles);
                    if (d == tiles) std::fprintf(stderr, "\n");
                }
            }
            rays += local.rays;
            capped += local.capped;
        };
        int threads = settings_.threads > 0 ? settings_.threads : int(std::thread::hardware_concurrency());
        threads = std::clamp(threads, 1, tiles);
        std::vector<std::thread> pool;
        for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
        worker();
        for (auto& th : pool) th.join();
        if (pool_lambda) apply_pooled_lambda(primaries, spp, out);
        out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        out.rays = rays;
        out.capped_walks = capped;
        out.paths = std::uint64_t(w) * std::uint64_t(h) * std::uint64_t(spp);
        return out;
    }

    /// Radiance along one camera ray (for tests); `count` counts traced rays and capped walks.
    /// `from` says how emission met by `ray` is weighted (Arrival: whole for a camera ray).
    Rgb<T> radiance(Ray<T> ray, S& sampler, PathCounters& count, T* lambda_out = nullptr,
                    PrimaryDirect<T>* primary = nullptr, Arrival<T> from = {}) const {
        Rgb<T> L(T(0)), F(T(1));
        for (int depth = 0;; ++depth) {
            if (depth == settings_.max_depth) {
                ++count.capped;
                break;
            }
            StoreHit<T> hit;
            ++count.rays;
            if (!accel_.closest_hit(ray, hit)) {
                if constexpr (Env) L += F * scene_.environment->eval(ray.direction) * environment_weight(from, ray.direction);
                break;
            }
            const std::uint32_t tri = hit.id;
            const Material<T>& m = scene_.materials[scene_.material_of[tri]];
            const Vec3<T> ng = scene_.normal(tri);
            const bool front = glm::dot(ng, ray.direction) < T(0);
            const Vec3<T> n = front ? ng : -ng;
            const auto [x, err] = surface_point(hit);  // not captured by any lambda (clang 14)
            if (front && m.emissive()) L += F * m.emission * emission_weight(from, ray, hit);

            if (m.specular()) {
                if (!specular_step(m, ShadingPoint<T>{x, err, n, {}, nullptr}, ng, depth, sampler, ray, F, L)) break;
                from = Arrival<T>{};
                continue;
            }

            const Frame<T> frame = Frame<T>::from_normal(n);
            const SurfaceBrdf<T> brdf(m, frame.to_local(-ray.direction));
            const ShadingPoint<T> sp{x, err, n, frame, &brdf};
            if constexpr (!D::collects_emission) {
                L += F * direct(sp, sampler, count.rays, depth == 0 ? lambda_out : nullptr, depth == 0 ? primary : nullptr);
            }
            if constexpr (Points) L += F * point_lights(sp, count.rays);

            const ScatterSample<T, 3> s = scatter_step(brdf, F, sampler, depth);
            if constexpr (R::has_radiance_estimate) L += F * s.offset;
            if (s.terminated()) break;
            F *= s.weight;
            if (F.max() <= T(0) || !F.is_finite()) break;  // nothing more can contribute
            ray = spawn(sp, frame.to_world(s.direction));
            if constexpr (!D::collects_emission) from = Arrival<T>{true, brdf.sampling_pdf(s.direction)};
        }
        return L;
    }

    /// A mirror or dielectric vertex: the deterministic direction (Fresnel choice for
    /// dielectrics), then the roulette on the one lobe. Updates ray, F and L (the roulette's
    /// offset); false when the walk stops.
    bool specular_step(const Material<T>& m, const ShadingPoint<T>& sp, const Vec3<T>& ng, int depth, S& sampler,
                       Ray<T>& ray, Rgb<T>& F, Rgb<T>& L) const {
        const Vec3<T>& n = sp.n;
        Vec3<T> wi;
        Rgb<T> albedo = m.ks;
        if (m.kind == MaterialKind::mirror) {
            wi = ray.direction - n * (T(2) * glm::dot(ray.direction, n));
        } else {
            wi = refract_or_reflect(ray.direction, ng, m.ior, sampler.get_1d());
            albedo = Rgb<T>(T(1));
        }
        const std::array<Rgb<T>, 1> lobes{albedo};
        const auto sel = select_lobe(roulette_, F, std::span<const Rgb<T>>(lobes), sampler.get_1d(), depth);
        if constexpr (R::has_radiance_estimate) L += F * sel.offset;
        if (sel.terminated()) return false;
        F *= albedo / sel.probability[0];
        ray = spawn(sp, wi);
        return true;
    }

    /// Roulette, lobe choice and direction at a diffuse/glossy vertex, with the BRDF-selection
    /// estimator of settings (000 section 2.1).
    ScatterSample<T, 3> scatter_step(const SurfaceBrdf<T>& brdf, const Rgb<T>& F, S& sampler, int depth) const {
        const T u_select = sampler.get_1d();
        const Vec2<T> u_dir = sampler.get_2d();
        switch (settings_.selection) {
            case BrdfSelection::decomposition:
                return scatter<BrdfSelection::decomposition>(brdf, roulette_, F, u_select, u_dir, depth);
            case BrdfSelection::weighted:
                return scatter<BrdfSelection::weighted>(brdf, roulette_, F, u_select, u_dir, depth);
            default: return scatter<BrdfSelection::mis>(brdf, roulette_, F, u_select, u_dir, depth);
        }
    }

    /// Pilot observations for 000 section 2.3's radiance-estimate roulette: at the first
    /// diffuse vertex of `n` camera paths, the albedo a and the one-sample reflected radiance
    /// X = (w/p) L_in (L_in traced by this tracer, so unbiased), `repeats` of them per vertex
    /// (consecutive; more than 1 for estimate_goodness_floor). X is exactly what the
    /// roulette decides about, what a terminated walk loses: with light sampling, emission
    /// met by the continued ray counts only with the BRDF sample's MIS weight (the rest is in
    /// the vertex's light samples), as in the walk. A direction the BRDF cannot sample gives
    /// X = 0, as in the walk.
    std::vector<RoulettePilotSample<T, 3>> pilot_samples(const S& prototype, int n, int repeats = 1) const {
        S sampler = prototype;
        std::vector<RoulettePilotSample<T, 3>> out;
        repeats = std::max(repeats, 1);
        out.reserve(std::size_t(std::max(n, 0)) * std::size_t(repeats));
        PathCounters count;
        const std::uint64_t pixels = std::uint64_t(settings_.width) * std::uint64_t(settings_.height);
        for (int i = 0; i < n; ++i) {
            // Pixels spread over the whole image (an odd multiplier not divisible by 3 permutes
            // the indices of a w x h image with w h = 2^k 3^j; any other size is still covered
            // widely), not the first rows: the fit must see every part of the scene.
            const std::uint64_t k = (std::uint64_t(i) * 0x9E3779B1u) % pixels;
            const int x = int(k % std::uint64_t(settings_.width)), y = int(k / std::uint64_t(settings_.width));
            const Ray<T> ray = camera_ray(x, y, std::uint64_t(0x9000000 + i), sampler);
            StoreHit<T> hit;
            if (!accel_.closest_hit(ray, hit)) continue;
            const Material<T>& m = scene_.materials[scene_.material_of[hit.id]];
            if (m.specular()) continue;
            const Vec3<T> ng = scene_.normal(hit.id);
            const Vec3<T> nn = glm::dot(ng, ray.direction) < T(0) ? ng : -ng;
            const auto [p, err] = surface_point(hit);
            const Frame<T> frame = Frame<T>::from_normal(nn);
            const SurfaceBrdf<T> brdf(m, frame.to_local(-ray.direction));
            for (int j = 0; j < repeats; ++j) {
                const Vec3<T> wi = sample_brdf(brdf, sampler.get_2d());
                const T pdf = brdf.sampling_pdf(wi);
                Rgb<T> X(T(0));
                if (pdf > T(0) && wi.z > T(0))
                    X = brdf.f(wi) * (wi.z / pdf) *
                        radiance(spawn(ShadingPoint<T>{p, err, nn, {}, nullptr}, frame.to_world(wi)), sampler, count, nullptr, nullptr,
                                 Arrival<T>{!D::collects_emission, pdf});
                out.push_back({m.kd + m.ks, X});
            }
        }
        return out;
    }

private:
    /// 000 section 3.1.1: replace each pixel's per-vertex-lambda primary direct light by
    /// a + lambda b with lambda = sum fg / sum gg over the pixel's neighbourhood.
    void apply_pooled_lambda(const std::vector<PrimaryDirect<T>>& p, int spp, RenderResult& out) const {
        const int w = settings_.width, h = settings_.height, r = settings_.lambda_filter_radius;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                Rgb<T> fg(T(0)), gg(T(0));
                for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy)
                    for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx) {
                        const auto& q = p[std::size_t(yy) * std::size_t(w) + std::size_t(xx)];
                        fg += q.fg;
                        gg += q.gg;
                    }
                const auto& q = p[std::size_t(y) * std::size_t(w) + std::size_t(x)];
                Rgb<float>& pixel = out.image.at(x, y);
                T lambda_mean = 0;
                for (std::size_t c = 0; c < 3; ++c) {
                    const T lambda = gg[c] > T(0) ? fg[c] / gg[c] : T(0);
                    pixel[c] += float((q.a[c] + lambda * q.b[c] - q.used[c]) / T(spp));
                    lambda_mean += lambda / T(3);
                }
                out.lambda.at(x, y) = float(lambda_mean);
            }
    }

    void render_pixel(int x, int y, int spp, S& sampler, RenderResult& out, PathCounters& count,
                      PrimaryDirect<T>* primary) const {
        Rgb<T> mean(T(0)), m2(T(0));
        T lambda_sum = 0;
        int lambda_count = 0;
        for (int i = 0; i < spp; ++i) {
            const Ray<T> ray = camera_ray(x, y, std::uint64_t(i), sampler);
            T lambda = std::numeric_limits<T>::quiet_NaN();
            PrimaryDirect<T> pd;
            Rgb<T> L = radiance(ray, sampler, count, &lambda, primary ? &pd : nullptr);
            if (!L.is_finite()) L = Rgb<T>(T(0));  // never let one sample poison a pixel
            else if (primary && pd.a.is_finite() && pd.b.is_finite()) {
                primary->used += pd.used;
                primary->a += pd.a;
                primary->b += pd.b;
                primary->fg += pd.fg;
                primary->gg += pd.gg;
            }
            if (!std::isnan(lambda)) {
                lambda_sum += lambda;
                ++lambda_count;
            }
            const Rgb<T> delta = L - mean;
            mean += delta / T(i + 1);
            m2 += delta * (L - mean);
        }
        for (std::size_t c = 0; c < 3; ++c) {
            out.image.at(x, y)[c] = float(mean[c]);
            out.variance.at(x, y)[c] = spp > 1 ? float(m2[c] / T(spp - 1) / T(spp)) : 0.0f;
        }
        out.lambda.at(x, y) = lambda_count ? float(lambda_sum / T(lambda_count)) : 0.0f;
    }

    /// Starts sample `index` of pixel (x, y) and returns its camera ray: through a jittered
    /// point of the pixel, or through its centre when pixel_jitter is off (the pixel sample is
    /// drawn either way, so the sampler's later dimensions stay the same).
    Ray<T> camera_ray(int x, int y, std::uint64_t index, S& sampler) const {
        sampler.start_pixel_sample(x, y, index);
        Vec2<T> p = sampler.get_pixel_2d();
        if (!settings_.pixel_jitter) p = Vec2<T>(T(0.5));
        const T aspect = T(settings_.width) / T(settings_.height);
        return scene_.camera.ray((T(x) + p.x) / T(settings_.width), (T(y) + p.y) / T(settings_.height), aspect);
    }

    /// gamma(n) = n u / (1 - n u), u = unit roundoff: the relative error bound of n roundings.
    static constexpr T gamma(int n) {
        const T u = std::numeric_limits<T>::epsilon() / T(2);
        return T(n) * u / (T(1) - T(n) * u);
    }

    /// Bound on the rounding error, per axis, of a point computed from vertices whose largest
    /// coordinate is m, and of the triangle tests' distances to their planes: gamma(16) m on
    /// every axis. Interpolation alone errs by gamma(7) sum |b_i v_i| per axis (Pharr, Jakob,
    /// Humphreys 2023, section 6.8.5), but an intersector mixes the axes (cross products), so
    /// the floor at y = 0 of a box 1 wide still has distance errors of ulps of 1, not of 0.
    static Vec3<T> coordinate_error(T m) { return Vec3<T>(gamma(16) * m); }

    /// The hit point interpolated from the triangle's vertices by the hit's barycentrics, and
    /// its error bound. Unlike o + t d, whose error grows with the ray's length and origin, the
    /// bound depends only on the triangle's own coordinates.
    std::pair<Vec3<T>, Vec3<T>> surface_point(const StoreHit<T>& hit) const {
        const auto& v = scene_.triangles[hit.id];
        const T b0 = T(1) - hit.u - hit.v;
        const Vec3<T> p = v[0] * b0 + v[1] * hit.u + v[2] * hit.v;
        const Vec3<T> m = glm::max(glm::max(glm::abs(v[0]), glm::abs(v[1])), glm::abs(v[2]));
        return {p, coordinate_error(std::max({m.x, m.y, m.z}))};
    }

    /// Origin of a ray leaving point p (rounding error `err` per axis) of a surface with normal
    /// n towards `dir`: p moved along n, to the side dir leaves to, past its error bound, and
    /// each coordinate then rounded away from the surface (Pharr, Jakob, Humphreys 2023, section
    /// 6.8.6). The offset scales with the coordinates' own rounding, so the same scene renders
    /// the same image at any translation and scale float resolves.
    static Vec3<T> offset_origin(const Vec3<T>& p, const Vec3<T>& err, const Vec3<T>& n, const Vec3<T>& dir) {
        const T d = glm::dot(glm::abs(n), err) * T(2);
        const Vec3<T> offset = glm::dot(dir, n) >= T(0) ? n * d : -n * d;
        Vec3<T> po = p + offset;
        for (int i = 0; i < 3; ++i) {
            if (offset[i] > T(0)) po[i] = std::nextafter(po[i], infinity<T>);
            else if (offset[i] < T(0)) po[i] = std::nextafter(po[i], -infinity<T>);
        }
        return po;
    }

    /// A ray leaving shading point sp in direction dir.
    static Ray<T> spawn(const ShadingPoint<T>& sp, const Vec3<T>& dir) {
        return Ray<T>{offset_origin(sp.x, sp.err, sp.n, dir), dir, T(0), infinity<T>};
    }

    /// Shadow ray from sp to point y (rounding error y_err, on a surface of normal ny; zero
    /// for a point light), both ends offset off their surfaces, stopping just short of y.
    bool visible(const ShadingPoint<T>& sp, const Vec3<T>& y, const Vec3<T>& y_err, const Vec3<T>& ny,
                 std::uint64_t& rays) const {
        const Vec3<T> xo = offset_origin(sp.x, sp.err, sp.n, y - sp.x);
        const Vec3<T> yo = offset_origin(y, y_err, ny, xo - y);
        ++rays;
        return !accel_.any_hit(Ray<T>{xo, yo - xo, T(0), T(1) - T(sizeof(T) == 4 ? 1e-4 : 1e-9)});
    }
    bool visible(const ShadingPoint<T>& sp, const PolygonLight<T, 3>& light, const Vec3<T>& y,
                 std::uint64_t& rays) const {
        // A point of the light polygon is a convex combination of its vertices.
        T m = 0;
        for (const auto& v : light.sampler().vertices()) m = std::max({m, std::abs(v.x), std::abs(v.y), std::abs(v.z)});
        return visible(sp, y, coordinate_error(m), light.sampler().normal(), rays);
    }

    static T balance(T a, T b) { return a + b > T(0) ? a / (a + b) : T(0); }

    /// Dielectric: Fresnel reflectance chooses reflection or refraction (ior relative to
    /// the side the normal points away from).
    static Vec3<T> refract_or_reflect(const Vec3<T>& d, const Vec3<T>& ng, T ior, T u) {
        const Vec3<T> dn = safe_normalize(d);
        T cos_i = -glm::dot(dn, ng);
        Vec3<T> n = ng;
        T eta = T(1) / ior;
        if (cos_i < T(0)) {
            cos_i = -cos_i;
            n = -ng;
            eta = ior;
        }
        const T sin2_t = eta * eta * std::max(T(0), T(1) - cos_i * cos_i);
        const Vec3<T> reflected = dn + n * (T(2) * cos_i);
        if (sin2_t >= T(1)) return reflected;
        const T cos_t = std::sqrt(T(1) - sin2_t);
        const T rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t), rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
        const T fresnel = T(0.5) * (rs * rs + rp * rp);
        if (u < fresnel) return reflected;
        return dn * eta + n * (eta * cos_i - cos_t);
    }

    /// Index of the area light chosen by u (proportional to power); its probability.
    std::size_t pick_light(T u, T& prob) const {
        const T target = u * light_power_;
        std::size_t i = std::size_t(std::upper_bound(light_cdf_.begin(), light_cdf_.end(), target) - light_cdf_.begin());
        i = std::min(i, lights_.size() - 1);
        prob = (light_cdf_[i] - (i ? light_cdf_[i - 1] : T(0))) / light_power_;
        return i;
    }

    Rgb<T> direct(const ShadingPoint<T>& sp, S& sampler, std::uint64_t& rays, T* lambda_out,
                  PrimaryDirect<T>* primary) const {
        Rgb<T> L(T(0));
        if constexpr (std::is_same_v<D, CorrelatedDirect>) {
            if (!lights_.empty()) {
                std::array<Vec2<T>, 64> u;
                const std::size_t k = std::size_t(std::clamp(settings_.light_samples, 1, 64));
                T lambda_sum = 0;
                for (const auto& light : lights_) {
                    for (std::size_t i = 0; i < k; ++i) u[i] = sampler.get_2d();
                    if (settings_.estimator == DirectEstimator::importance) {
                        // f/p alone: no main part, so no form factor is computed.
                        const T area = light.sampler().area();
                        for (std::size_t i = 0; i < k; ++i) {
                            const Vec3<T> y = light.sampler().sample(u[i]);
                            const T G = light.geometry(sp.x, sp.n, y) * area;
                            if (G > T(0) && visible(sp, light, y, rays))
                                L += light.radiance() * sp.brdf->f(sp.frame.to_local(safe_normalize(y - sp.x))) * (G / T(k));
                        }
                        continue;
                    }
                    const Rgb<T> fr_approx = sp.brdf->kd() / pi<T>;
                    const auto res = correlated_direct(
                        light, sp.x, sp.n, [&](const Vec3<T>& wi) { return sp.brdf->f(sp.frame.to_local(wi)); },
                        fr_approx, [&](const Vec3<T>&, const Vec3<T>& b) { return visible(sp, light, b, rays); },
                        std::span<const Vec2<T>>(u.data(), k));
                    switch (settings_.estimator) {
                        case DirectEstimator::importance: L += res.importance; break;
                        case DirectEstimator::correlated: L += res.correlated; break;
                        default: L += res.combined; break;
                    }
                    if (primary) {
                        for (std::size_t c = 0; c < 3; ++c) {
                            primary->a[c] += res.importance[c];
                            primary->b[c] += res.main_part[c] - res.stats[c].mean_g;
                            primary->fg[c] += res.stats[c].comoment_fg;
                            primary->gg[c] += res.stats[c].comoment_gg;
                        }
                        primary->used += res.combined;
                    }
                    lambda_sum += res.lambda.mean();
                }
                if (lambda_out) *lambda_out = lambda_sum / T(lights_.size());
            }
        } else if constexpr (std::is_same_v<D, MisDirect>) {
            const int k = std::max(1, settings_.light_samples);
            for (int i = 0; i < k; ++i) L += mis_area_light(sp, sampler, rays, T(k));
        }
        if constexpr (Env) L += mis_environment(sp, sampler, rays);
        return L;
    }

    /// Light-sampling density (solid angle, light chosen by power) of the direction towards a
    /// point of area light `l` at squared distance r2, seen under cosine cos_l there.
    T area_light_pdf(const AreaLight<T>& l, T r2, T cos_l) const {
        return l.emission.luminance() / light_power_ * r2 / cos_l;
    }

    /// One light sample of the area lights (light by power, then uniform on it). With k light
    /// samples per vertex and the continuation ray as the one BRDF sample, the balance
    /// heuristic over both strategies (Veach and Guibas 1995, with sample counts) gives each
    /// light sample f Le cos / (k p_light + p_brdf) (emission_weight gives the BRDF sample's).
    Rgb<T> mis_area_light(const ShadingPoint<T>& sp, S& sampler, std::uint64_t& rays, T k) const {
        const T u_light = sampler.get_1d();
        const Vec2<T> u_point = sampler.get_2d();
        if (lights_.empty()) return Rgb<T>(T(0));
        T prob;
        const std::size_t li = pick_light(u_light, prob);
        const auto& light = lights_[li];
        const Vec3<T> y = light.sampler().sample(u_point);
        const Vec3<T> d = y - sp.x;
        const T r2 = glm::dot(d, d);
        const Vec3<T> wi = d / std::sqrt(r2);
        const T cos_l = -glm::dot(wi, light.sampler().normal());
        const Vec3<T> wl = sp.frame.to_local(wi);
        if (!(cos_l > T(0)) || wl.z <= T(0)) return Rgb<T>(T(0));
        const T pdf_light = prob / light.sampler().area() * r2 / cos_l;
        const Rgb<T> f = sp.brdf->f(wl);
        if (f.max() <= T(0) || !visible(sp, light, y, rays)) return Rgb<T>(T(0));
        return light.radiance() * f * (wl.z / (k * pdf_light + sp.brdf->sampling_pdf(wl)));
    }

    /// Weight of area-light emission met at `hit` by `ray`, which left a vertex as `from` says.
    T emission_weight(const Arrival<T>& from, const Ray<T>& ray, const StoreHit<T>& hit) const {
        if (!from.lights_sampled) return T(1);
        if constexpr (!std::is_same_v<D, MisDirect>) {
            return T(0);  // CorrelatedDirect: its light samples estimate the area lights whole
        } else {
            const std::int32_t li = scene_.light_of[hit.id];
            if (li < 0) return T(1);  // emissive but not a sampled light: only BRDF sampling finds it
            const auto& al = scene_.area_lights[std::size_t(li)];
            const T len2 = glm::dot(ray.direction, ray.direction);
            const T cos_l = -glm::dot(ray.direction, al.normal) / std::sqrt(len2);
            if (!(cos_l > T(0))) return T(0);
            const T k = T(std::max(1, settings_.light_samples));
            const T pdf_light = area_light_pdf(al, hit.t * hit.t * len2, cos_l);
            return from.pdf / (from.pdf + k * pdf_light);
        }
    }

    /// Weight of the environment seen along `dir` by a ray that left a vertex as `from` says.
    T environment_weight(const Arrival<T>& from, const Vec3<T>& dir) const {
        if (!from.lights_sampled) return T(1);
        return balance(from.pdf, scene_.environment->pdf(safe_normalize(dir)));
    }

    static Vec3<T> sample_brdf(const SurfaceBrdf<T>& brdf, Vec2<T> u) {
        if (brdf.lobe_count() == 1) return brdf.sample(0, u);
        const T a0 = brdf.albedo(0).luminance(), a1 = brdf.albedo(1).luminance();
        const T p0 = a0 + a1 > T(0) ? a0 / (a0 + a1) : T(1);
        if (u.x < p0) {
            u.x = std::min(u.x / p0, T(1) - std::numeric_limits<T>::epsilon());
            return brdf.sample(0, u);
        }
        u.x = std::min((u.x - p0) / (T(1) - p0), T(1) - std::numeric_limits<T>::epsilon());
        return brdf.sample(1, u);
    }

    /// One environment-map sample, weighted by the balance heuristic against the BRDF sample
    /// (the continuation ray, weighted by environment_weight where it escapes).
    Rgb<T> mis_environment(const ShadingPoint<T>& sp, S& sampler, std::uint64_t& rays) const {
        const auto& env = *scene_.environment;
        const Vec2<T> u_env = sampler.get_2d();
        T pdf_env;
        const Vec3<T> we = env.sample(u_env, pdf_env);
        const Vec3<T> wl = sp.frame.to_local(we);
        if (!(pdf_env > T(0)) || wl.z <= T(0)) return Rgb<T>(T(0));
        const Rgb<T> f = sp.brdf->f(wl);
        if (f.max() <= T(0)) return Rgb<T>(T(0));
        ++rays;
        if (accel_.any_hit(spawn(sp, we))) return Rgb<T>(T(0));
        return env.eval(we) * f * (wl.z * balance(pdf_env, sp.brdf->sampling_pdf(wl)) / pdf_env);
    }

    Rgb<T> point_lights(const ShadingPoint<T>& sp, std::uint64_t& rays) const {
        Rgb<T> L(T(0));
        for (const auto& pl : scene_.point_lights) {
            const Vec3<T> d = pl.position - sp.x;
            const T r2 = glm::dot(d, d);
            const Vec3<T> wl = sp.frame.to_local(d / std::sqrt(r2));
            if (wl.z <= T(0)) continue;  // behind the shading plane: culled before any ray
            if (visible(sp, pl.position, Vec3<T>(T(0)), Vec3<T>(T(0)), rays)) L += pl.intensity * sp.brdf->f(wl) * (wl.z / r2);
        }
        return L;
    }

    const Scene<T>& scene_;
    const Accel& accel_;
    R roulette_;
    RenderSettings settings_;
    std::vector<PolygonLight<T, 3>> lights_;
    std::vector<T> light_cdf_;
    T light_power_ = 0;
};

}  // namespace glint
