// glint/tracer/renderer.hpp: the renderer around an integrator.
//
// The renderer owns what every image needs whatever the light transport: 16x16 tiles over
// std::thread workers (or the host's Executor), progress reported to the host's callback (the
// library prints nothing), the statistics (rays, paths, capped walks, seconds)
// and each pixel's mean and variance, which it hands to a film policy (Film, the default, keeps
// the image's layers; any FilmPolicy plugs in). For each pixel sample it asks its camera
// policy for a ray and the integrator (PathTracer, VplIntegrator, or any type that satisfies
// Integrator) for the radiance along it; after all samples it lets the integrator finish the
// film once (correlated direct lighting pools its lambda there, Szécsi 2009, §3.1.1, and adds its
// lambda layer; the VPL method adds its indirect layer). An integrator that can continue from
// a hit traced beforehand (FirstHitIntegrator: the path tracer) gets a tile's camera rays
// traced as streams of 256 pixel samples (16-ray packets through MeshBvh; docs/tracer.md
// measures what that gains). Every pixel sample draws from the sampler's stream for (x, y,
// sample index), so the image does not depend on the thread count, the order tiles are
// rendered in or whether the camera rays went as a stream.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <concepts>
#include <cstdint>
#include <functional>
#include <mutex>
#include <span>
#include <vector>

#include <glint/core/math.hpp>
#include <glint/core/parallel.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/sampling/sampler.hpp>
#include <glint/tracer/film.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

/// What the renderer reports after each finished tile: tiles finished and in all, and the
/// seconds since the render started.
struct RenderProgress {
    /// Tiles finished so far, including the one just finished (1 to tiles).
    int tiles_done = 0;
    /// Tiles in the whole image (16x16 pixels each, the last row and column possibly smaller).
    int tiles = 0;
    /// Wall-clock seconds since render() started.
    double seconds = 0;
};

/// The image's settings; each integrator has its own (PathTracerSettings, VplSettings).
struct RenderSettings {
    /// Image width in pixels (> 0).
    int width = 256;
    /// Image height in pixels (> 0).
    int height = 256;
    /// Samples per pixel; values below 1 count as 1.
    int spp = 16;
    int threads = 0;  ///< workers; 0: std::thread::hardware_concurrency()
    /// Runs the workers on the host's threads (empty: glint's own std::threads).
    Executor executor{};
    /// Called after each finished tile, from the rendering threads but never two calls at once
    /// (empty: nothing reported).
    std::function<void(const RenderProgress&)> progress{};
    /// Camera rays through uniformly jittered points of each pixel (the pixel's area average,
    /// the default) or through its centre only. With centres, an image estimates the radiance
    /// along fixed rays, so that its error against a reference of the same rays is light
    /// transport's alone: comparisons of estimators (bench_convergence) are not diluted by
    /// the pixel-footprint noise at silhouettes and light edges that every method shares.
    bool pixel_jitter = true;
    /// The sample index of each pixel's first sample: a render of samples first_sample to
    /// first_sample + spp - 1, so that progressive passes continue one sequence (a Halton
    /// sampler's pixel positions are not randomized by its seed: passes must not restart it).
    std::uint64_t first_sample = 0;
};

/// What a render measured.
struct RenderStats {
    /// Wall-clock seconds of the whole render, the integrator's finish() included.
    double seconds = 0;
    std::uint64_t rays = 0;          ///< closest-hit plus shadow rays
    std::uint64_t paths = 0;         ///< camera paths (pixel samples)
    std::uint64_t capped_walks = 0;  ///< walks cut by the integrator's depth cap (biased)
};

/// A render on the default film.
struct RenderResult : Film, RenderStats {};

/// What an integrator returns for one camera ray: the radiance, the rays it traced and
/// whether its walk was cut by a depth cap.
template <Scalar T>
struct PathSample {
    /// Radiance along the ray (linear RGB); a non-finite value is counted as zero by the renderer.
    Rgb<T> L{T(0)};
    /// Rays traced for this sample (closest-hit plus shadow rays).
    std::uint64_t rays = 0;
    /// Whether the walk was cut by a depth cap rather than ended by roulette or a miss (biased).
    bool capped = false;
};

/// A camera policy: the ray of sample `index` of pixel (x, y), drawn from `sampler` (which it
/// starts at that pixel sample).
template <class C, class S>
concept CameraPolicy = requires(const C& c, S& sampler, int x, std::uint64_t index) {
    typename C::scalar_type;
    { c.ray(x, x, index, sampler) } -> std::same_as<Ray<typename C::scalar_type>>;
};

/// The scene's pinhole camera over a width x height image: rays through a jittered point of
/// each pixel, or through its centre when pixel_jitter is off (the pixel sample is drawn
/// either way, so the sampler's later dimensions stay the same).
template <Scalar T>
class PixelCamera {
public:
    /// The floating-point type of the rays it makes.
    using scalar_type = T;
    /// Over `camera`, with the image size and pixel_jitter of `s` (height must be > 0).
    PixelCamera(const Camera<T>& camera, const RenderSettings& s)
        : camera_(camera), width_(s.width), height_(s.height), jitter_(s.pixel_jitter) {}

    /// The world-space ray of sample `index` of pixel (x, y), (0, 0) at the top left; starts
    /// `sampler` at that pixel sample and draws its 2D pixel sample.
    template <class S>
        requires Sampler<S, T>
    Ray<T> ray(int x, int y, std::uint64_t index, S& sampler) const {
        sampler.start_pixel_sample(x, y, index);
        Vec2<T> p = sampler.get_pixel_2d();
        if (!jitter_) p = Vec2<T>(T(0.5));
        const T aspect = T(width_) / T(height_);
        return camera_.ray((T(x) + p.x) / T(width_), (T(y) + p.y) / T(height_), aspect);
    }

private:
    Camera<T> camera_;
    int width_, height_;
    bool jitter_;
};

/// An integrator that needs scratch state of its own per rendering thread (a visibility
/// policy's caches): make_thread_state() makes one for each thread, which passes it to every
/// radiance() it calls.
template <class I>
concept ThreadStateIntegrator = requires(const I& in) {
    { in.make_thread_state() } -> std::same_as<typename I::thread_state>;
};

/// An integrator: the radiance along a camera ray (with the thread's thread_state where it has
/// one), with statistics of its own per pixel (`pixel_state`, an empty struct when it keeps
/// none) that it turns into values of film F once, in finish(), after every sample is taken.
/// `states` holds one pixel_state per pixel, row by row; `state` is its pixel's.
template <class I, class S, class F = Film>
concept Integrator =
    std::default_initializable<typename I::pixel_state> &&
    requires(const I& in, F& film, std::span<const typename I::pixel_state> states) { in.finish(film, states); } &&
    ((ThreadStateIntegrator<I> &&
      requires(const I& in, const Ray<typename I::scalar_type>& ray, S& sampler, typename I::pixel_state& state,
               typename I::thread_state& thread) {
          { in.radiance(ray, sampler, state, thread) } -> std::same_as<PathSample<typename I::scalar_type>>;
      }) ||
     (!ThreadStateIntegrator<I> &&
      requires(const I& in, const Ray<typename I::scalar_type>& ray, S& sampler, typename I::pixel_state& state) {
          { in.radiance(ray, sampler, state) } -> std::same_as<PathSample<typename I::scalar_type>>;
      }));

/// An integrator that continues camera paths from closest hits traced beforehand, so that the
/// renderer traces a tile's camera rays as one stream (packets of 16 through MeshBvh):
/// first_hits(rays, hits) finds them (hits start empty), radiance(ray, hit, sampler, state[,
/// thread]) gives the same sample as radiance(ray, sampler, state[, thread]) from `hit`.
template <class I, class S>
concept FirstHitIntegrator =
    Integrator<I, S> &&
    requires(const I& in, std::span<const Ray<typename I::scalar_type>> rays,
             std::span<StoreHit<typename I::scalar_type>> hits) { in.first_hits(rays, hits); } &&
    ((ThreadStateIntegrator<I> &&
      requires(const I& in, const Ray<typename I::scalar_type>& ray, const StoreHit<typename I::scalar_type>& hit,
               S& sampler, typename I::pixel_state& state, typename I::thread_state& thread) {
          { in.radiance(ray, hit, sampler, state, thread) } -> std::same_as<PathSample<typename I::scalar_type>>;
      }) ||
     (!ThreadStateIntegrator<I> &&
      requires(const I& in, const Ray<typename I::scalar_type>& ray, const StoreHit<typename I::scalar_type>& hit,
               S& sampler, typename I::pixel_state& state) {
          { in.radiance(ray, hit, sampler, state) } -> std::same_as<PathSample<typename I::scalar_type>>;
      }));

namespace detail {

struct NoThreadState {};

/// A rendering thread's scratch state for integrator `in` (nothing for most integrators).
template <class I>
auto make_thread_state(const I& in) {
    if constexpr (ThreadStateIntegrator<I>) return in.make_thread_state();
    else return NoThreadState{};
}

}  // namespace detail

/// Renders images with camera policy C (a CameraPolicy, e.g. PixelCamera): tiles over threads,
/// progress, statistics and each pixel's mean and variance of the mean, with any Integrator.
/// Renders are deterministic for a given sampler prototype, whatever the thread count.
template <class C>
class Renderer {
public:
    /// A renderer that copies `camera` and `settings` (the image size, spp, threads, progress).
    Renderer(const C& camera, const RenderSettings& settings) : camera_(camera), settings_(settings) {}

    /// Renders with `integrator` and one sampler per thread, copied from `prototype`, on the
    /// default film.
    template <class I, class S>
        requires Integrator<I, S> && CameraPolicy<C, S>
    RenderResult render(const I& integrator, const S& prototype) const {
        RenderResult out;
        static_cast<RenderStats&>(out) = render(integrator, prototype, static_cast<Film&>(out));
        return out;
    }

    /// Renders on `film`, a FilmPolicy.
    template <class I, class S, class F>
        requires Integrator<I, S, F> && CameraPolicy<C, S> && FilmPolicy<F, typename I::scalar_type>
    RenderStats render(const I& integrator, const S& prototype, F& film) const {
        const int w = settings_.width, h = settings_.height, tile = 16, tx = (w + tile - 1) / tile;
        const int tiles = tx * ((h + tile - 1) / tile);
        film.resize(w, h);
        std::vector<typename I::pixel_state> states(std::size_t(w) * std::size_t(h));
        int done = 0;  // tiles finished (counted under progress_mutex_)
        std::atomic<std::uint64_t> rays{0}, capped{0};
        const auto start = std::chrono::steady_clock::now();
        const auto report = [&] {
            if (!settings_.progress) return;
            std::lock_guard lock(progress_mutex_);
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            settings_.progress(RenderProgress{++done, tiles, seconds});
        };
        detail::parallel_blocks(tiles, settings_.threads, [&](std::atomic<int>& next) {
            S sampler = prototype;
            auto thread = detail::make_thread_state(integrator);
            TileStream<typename I::scalar_type> stream;
            Tally tally;
            for (int t = next++; t < tiles; t = next++) {
                const int x0 = (t % tx) * tile, y0 = (t / tx) * tile;
                if constexpr (FirstHitIntegrator<I, S>) {
                    tally += render_tile(integrator, x0, y0, sampler, std::span(states), thread, film, stream);
                } else {
                    for (int y = y0; y < std::min(y0 + tile, h); ++y)
                        for (int x = x0; x < std::min(x0 + tile, w); ++x)
                            tally += render_pixel(integrator, x, y, sampler, states[pixel_index(x, y)], thread, film);
                }
                report();
            }
            rays += tally.rays;
            capped += tally.capped;
        }, settings_.executor);
        integrator.finish(film, std::span<const typename I::pixel_state>(states));
        RenderStats out;
        out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        out.rays = rays;
        out.capped_walks = capped;
        out.paths = std::uint64_t(w) * std::uint64_t(h) * std::uint64_t(spp());
        return out;
    }

private:
    struct Tally {
        std::uint64_t rays = 0, capped = 0;
        Tally& operator+=(const Tally& o) {
            rays += o.rays;
            capped += o.capped;
            return *this;
        }
    };

    /// A pixel's running mean and sum of squared deviations (Welford's update).
    template <class T>
    struct PixelSum {
        Rgb<T> mean{T(0)}, m2{T(0)};
        int n = 0;
        /// Adds sample `s` (a non-finite radiance counts as zero) and counts it into `tally`.
        /// Compiled once: inlined into each loop, contraction into FMAs could round the
        /// variance differently for render_pixel() and render_tile().
        [[gnu::noinline]] void add(const PathSample<T>& s, Tally& tally) {
            tally.rays += s.rays;
            tally.capped += s.capped ? 1 : 0;
            const Rgb<T> L = s.L.is_finite() ? s.L : Rgb<T>(T(0));  // never let one sample poison a pixel
            const Rgb<T> delta = L - mean;
            mean += delta / T(++n);
            m2 += delta * (L - mean);
        }
        /// The mean and the variance of the mean into pixel (x, y) of `film`.
        template <class F>
        void store(F& film, int x, int y) const {
            film.set_pixel(x, y, mean, n > 1 ? m2 / T(n - 1) / T(n) : Rgb<T>(T(0)));
        }
    };

    /// A rendering thread's scratch for render_tile(): the tile's pixels, rays, hits and sums.
    template <class T>
    struct TileStream {
        std::vector<std::array<int, 2>> pixels;
        std::vector<Ray<T>> rays;
        std::vector<StoreHit<T>> hits;
        std::vector<PixelSum<T>> sums;
    };

    int spp() const { return std::max(1, settings_.spp); }
    std::size_t pixel_index(int x, int y) const { return std::size_t(y) * std::size_t(settings_.width) + std::size_t(x); }

    /// One sample of `integrator` along `ray`, from its closest hit `first` where given.
    template <class I, class S, class Th>
    static PathSample<typename I::scalar_type> sample(const I& integrator, const Ray<typename I::scalar_type>& ray,
                                                      const StoreHit<typename I::scalar_type>* first, S& sampler,
                                                      typename I::pixel_state& state, Th& thread) {
        if constexpr (FirstHitIntegrator<I, S>) {
            if constexpr (ThreadStateIntegrator<I>) return integrator.radiance(ray, *first, sampler, state, thread);
            else return integrator.radiance(ray, *first, sampler, state);
        } else {
            if constexpr (ThreadStateIntegrator<I>) return integrator.radiance(ray, sampler, state, thread);
            else return integrator.radiance(ray, sampler, state);
        }
    }

    /// The pixel's samples, their mean and the variance of the mean.
    template <class I, class S, class Th, class F>
    Tally render_pixel(const I& integrator, int x, int y, S& sampler, typename I::pixel_state& state, Th& thread,
                       F& film) const {
        PixelSum<typename I::scalar_type> sum;
        Tally tally;
        for (int i = 0; i < spp(); ++i) {
            const auto ray = camera_.ray(x, y, settings_.first_sample + std::uint64_t(i), sampler);
            sum.add(sample(integrator, ray, nullptr, sampler, state, thread), tally);
        }
        sum.store(film, x, y);
        return tally;
    }

    /// The tile at (x0, y0) through camera-ray streams: its pixels in 4 x 4 blocks, each pixel's
    /// samples in order, taken 256 at a time: their camera rays traced as one stream (16
    /// consecutive rays, a packet, are one pixel's samples or a few neighbours'), then each
    /// sample from its hit, the sampler restarted at the pixel sample as render_pixel() starts
    /// it: the same samples, the same image.
    template <class I, class S, class Th, class F, class T = typename I::scalar_type>
    Tally render_tile(const I& integrator, int x0, int y0, S& sampler, std::span<typename I::pixel_state> states,
                      Th& thread, F& film, TileStream<T>& ws) const {
        ws.pixels.clear();
        for (int b = 0; b < 256; ++b) {
            const int x = x0 + (b >> 4 & 3) * 4 + (b & 3), y = y0 + (b >> 6) * 4 + (b >> 2 & 3);
            if (x < settings_.width && y < settings_.height) ws.pixels.push_back({x, y});
        }
        ws.sums.assign(ws.pixels.size(), PixelSum<T>{});
        const std::size_t n = std::size_t(spp()), items = ws.pixels.size() * n, batch = 256;
        const auto start = [&](std::size_t j) {  // item j: sample j % n of pixel j / n
            const auto [x, y] = ws.pixels[j / n];
            return camera_.ray(x, y, settings_.first_sample + std::uint64_t(j % n), sampler);
        };
        Tally tally;
        for (std::size_t j0 = 0; j0 < items; j0 += batch) {
            const std::size_t m = std::min(batch, items - j0);
            ws.rays.resize(m);
            for (std::size_t j = 0; j < m; ++j) ws.rays[j] = start(j0 + j);
            ws.hits.assign(m, StoreHit<T>{});
            integrator.first_hits(std::span<const Ray<T>>(ws.rays), std::span<StoreHit<T>>(ws.hits));
            for (std::size_t j = 0; j < m; ++j) {
                start(j0 + j);  // starts the sampler at the pixel sample again
                const auto [x, y] = ws.pixels[(j0 + j) / n];
                ws.sums[(j0 + j) / n].add(sample(integrator, ws.rays[j], &ws.hits[j], sampler, states[pixel_index(x, y)], thread), tally);
            }
        }
        for (std::size_t k = 0; k < ws.pixels.size(); ++k) ws.sums[k].store(film, ws.pixels[k][0], ws.pixels[k][1]);
        return tally;
    }

    C camera_;
    RenderSettings settings_;
    mutable std::mutex progress_mutex_;
};

/// Renders `integrator` through the scene's camera (PixelCamera) with the renderer's settings.
template <Scalar T, class I, class S>
    requires Integrator<I, S> && CameraPolicy<PixelCamera<T>, S>
RenderResult render_image(const Scene<T>& scene, const RenderSettings& settings, const I& integrator, const S& sampler) {
    return Renderer<PixelCamera<T>>(PixelCamera<T>(scene.camera, settings), settings).render(integrator, sampler);
}

/// The same on a film of one's own (a FilmPolicy).
template <Scalar T, class I, class S, class F>
    requires Integrator<I, S, F> && CameraPolicy<PixelCamera<T>, S> && FilmPolicy<F, typename I::scalar_type>
RenderStats render_image(const Scene<T>& scene, const RenderSettings& settings, const I& integrator, const S& sampler,
                         F& film) {
    return Renderer<PixelCamera<T>>(PixelCamera<T>(scene.camera, settings), settings).render(integrator, sampler, film);
}

}  // namespace glint
