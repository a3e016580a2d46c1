// glint/tracer/environment.hpp: a latitude-longitude environment map with importance
// sampling, and a procedural sky with a sun for scenes that give no map.
//
// Directions: y is up; pixel (x, y) covers phi in [2 pi x / W, 2 pi (x+1) / W) and
// theta in [pi y / H, pi (y+1) / H), with d = (sin theta cos phi, cos theta, sin theta sin phi).
// The map is piecewise constant per pixel; directions are sampled with a density
// proportional to luminance * sin(theta) per pixel (marginal over rows, conditional within a
// row), so pdf(d) = p_pixel / (pixel solid angle), exactly consistent with eval().
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/image.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

template <Scalar T>
/// Radiance arriving from infinitely far away, by direction: a latitude-longitude RGB map
/// (layout in the header comment) with luminance-proportional importance sampling. Immutable
/// after construction, so one map serves all threads.
class EnvironmentMap {
public:
    /// A map over `image` (radiance per pixel, W/(m^2 sr) per band); builds the sampling tables
    /// in O(width * height). Throws glint::Error for an empty or all-black image or a negative
    /// or non-finite pixel.
    explicit EnvironmentMap(Image<Rgb<float>> image) : image_(std::move(image)) {
        const int w = image_.width, h = image_.height;
        if (w < 1 || h < 1) throw Error("EnvironmentMap: empty image");
        for (const auto& p : image_.pixels)
            if (!p.is_finite() || p.min() < 0.0f)
                throw Error("EnvironmentMap: pixels must be finite and non-negative");
        conditional_.assign(std::size_t(w) * std::size_t(h) + std::size_t(h), 0.0);
        marginal_.assign(std::size_t(h) + 1, 0.0);
        for (int y = 0; y < h; ++y) {
            const double s = std::sin(pi<double> * (y + 0.5) / h);
            double* row = &conditional_[std::size_t(y) * std::size_t(w + 1)];
            row[0] = 0;
            for (int x = 0; x < w; ++x) row[x + 1] = row[x] + weight(image_.at(x, y)) * s;
            marginal_[std::size_t(y) + 1] = marginal_[std::size_t(y)] + row[w];
        }
        if (!(marginal_[std::size_t(h)] > 0)) throw Error("EnvironmentMap: the map is black");
    }

    /// The radiance image the map was built from.
    const Image<Rgb<float>>& image() const { return image_; }

    /// Radiance arriving from direction d (any length; the value of the pixel d falls in,
    /// piecewise constant, no filtering).
    Rgb<T> eval(const Vec3<T>& d) const {
        int x, y;
        pixel_of(d, x, y);
        const Rgb<float>& p = image_.at(x, y);
        return Rgb<T>(T(p[0]), T(p[1]), T(p[2]));
    }

    /// Solid-angle density of sample() in direction d.
    T pdf(const Vec3<T>& d) const {
        int x, y;
        pixel_of(d, x, y);
        return T(pixel_probability(x, y) / pixel_solid_angle(y));
    }

    /// A direction drawn with density pdf(); returns its density in `pdf_out`.
    Vec3<T> sample(const Vec2<T>& u, T& pdf_out) const {
        const int w = image_.width, h = image_.height;
        const double total = marginal_[std::size_t(h)];
        const double ty = double(u.y) * total;
        int y = int(std::upper_bound(marginal_.begin(), marginal_.end(), ty) - marginal_.begin()) - 1;
        y = std::clamp(y, 0, h - 1);
        while (marginal_[std::size_t(y) + 1] - marginal_[std::size_t(y)] <= 0 && y > 0) --y;
        const double* row = &conditional_[std::size_t(y) * std::size_t(w + 1)];
        const double tx = double(u.x) * row[w];
        int x = int(std::upper_bound(row, row + w + 1, tx) - row) - 1;
        x = std::clamp(x, 0, w - 1);
        while (row[x + 1] - row[x] <= 0 && x > 0) --x;
        // Uniform within the pixel in phi and cos(theta) (uniform solid angle).
        const double fx = std::clamp((tx - row[x]) / std::max(row[x + 1] - row[x], 1e-300), 0.0, 1.0);
        const double fy = std::clamp((ty - marginal_[std::size_t(y)]) /
                                     std::max(marginal_[std::size_t(y) + 1] - marginal_[std::size_t(y)], 1e-300), 0.0, 1.0);
        const double phi = 2 * pi<double> * (x + fx) / w;
        const double c0 = std::cos(pi<double> * y / h), c1 = std::cos(pi<double> * (y + 1) / h);
        const double cos_t = c0 + (c1 - c0) * fy, sin_t = std::sqrt(std::max(0.0, 1 - cos_t * cos_t));
        pdf_out = T(pixel_probability(x, y) / pixel_solid_angle(y));
        return Vec3<T>(T(sin_t * std::cos(phi)), T(cos_t), T(sin_t * std::sin(phi)));
    }

    /// Integrals over the directions with phi in [phi0, phi1] and cos(theta) in [cos_lo, cos_hi]
    /// (0 <= phi0 <= phi1 <= 2 pi), exact for the piecewise-constant map: each pixel counts with
    /// the solid angle it shares with the region, (phi overlap) x (cos(theta) overlap).
    struct RegionIntegrals {
        Rgb<double> radiance{0.0};     ///< integral of L dw
        double luminance_squared = 0;  ///< integral of luminance(L)^2 dw
        double solid_angle = 0;        ///< The region's solid angle in sr (integral of dw).
    };
    /// The RegionIntegrals of the region given above; cost linear in the pixels it overlaps.
    RegionIntegrals integrate(double phi0, double phi1, double cos_lo, double cos_hi) const {
        const int w = image_.width, h = image_.height;
        RegionIntegrals out;
        for (int y = 0; y < h; ++y) {
            const double dz = std::min(cos_hi, std::cos(pi<double> * y / h)) -
                              std::max(cos_lo, std::cos(pi<double> * (y + 1) / h));
            if (!(dz > 0)) continue;
            const int x0 = std::max(0, int(phi0 / (2 * pi<double>) * w));
            const int x1 = std::min(w - 1, int(phi1 / (2 * pi<double>) * w));
            for (int x = x0; x <= x1; ++x) {
                const double dphi = std::min(phi1, 2 * pi<double> * (x + 1) / w) - std::max(phi0, 2 * pi<double> * x / w);
                if (!(dphi > 0)) continue;
                const Rgb<float>& p = image_.at(x, y);
                const double omega = dphi * dz, lum = double(p.luminance());
                out.radiance += Rgb<double>(p[0], p[1], p[2]) * omega;
                out.luminance_squared += lum * lum * omega;
                out.solid_angle += omega;
            }
        }
        return out;
    }

    /// A sky: gradient from `horizon` to `zenith` radiance, dark ground, and a sun disc of
    /// angular radius `sun_radius` with radiance `sun` in direction `sun_dir`.
    static EnvironmentMap sky(int width, int height, const Vec3<T>& sun_dir, const Rgb<float>& sun,
                              float sun_radius, const Rgb<float>& zenith, const Rgb<float>& horizon,
                              const Rgb<float>& ground) {
        Image<Rgb<float>> img(width, height);
        const Vec3<T> s = safe_normalize(sun_dir);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const double phi = 2 * pi<double> * (x + 0.5) / width, theta = pi<double> * (y + 0.5) / height;
                const Vec3d d(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
                Rgb<float> c;
                if (d.y >= 0) {
                    const float t = float(std::pow(d.y, 0.5));
                    c = horizon * (1.0f - t) + zenith * t;
                } else {
                    c = ground;
                }
                if (std::acos(std::clamp(glm::dot(d, Vec3d(s)), -1.0, 1.0)) < sun_radius) c += sun;
                img.at(x, y) = c;
            }
        return EnvironmentMap(std::move(img));
    }

private:
    static double weight(const Rgb<float>& p) { return std::max(1e-6, double(p.luminance())); }

    void pixel_of(const Vec3<T>& d, int& x, int& y) const {
        const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
        const double cos_t = len > 0 ? std::clamp(double(d.y) / len, -1.0, 1.0) : 1.0;
        double phi = std::atan2(double(d.z), double(d.x));
        if (phi < 0) phi += 2 * pi<double>;
        x = std::clamp(int(phi / (2 * pi<double>) * image_.width), 0, image_.width - 1);
        y = std::clamp(int(std::acos(cos_t) / pi<double> * image_.height), 0, image_.height - 1);
    }
    double pixel_probability(int x, int y) const {
        const double* row = &conditional_[std::size_t(y) * std::size_t(image_.width + 1)];
        return (row[x + 1] - row[x]) / marginal_[std::size_t(image_.height)];
    }
    double pixel_solid_angle(int y) const {
        const double c0 = std::cos(pi<double> * y / image_.height), c1 = std::cos(pi<double> * (y + 1) / image_.height);
        return 2 * pi<double> / image_.width * (c0 - c1);
    }

    Image<Rgb<float>> image_;
    std::vector<double> conditional_;  // per row: W + 1 cumulative weights
    std::vector<double> marginal_;     // H + 1 cumulative row weights
};

}  // namespace glint
