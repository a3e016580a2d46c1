// glint/tracer/film.hpp: what the renderer hands each pixel's estimate to. A film policy
// (FilmPolicy) receives every pixel's mean and the variance of that mean once; Film, the
// renderer's default, keeps them as images beside the layers an integrator adds when it
// finishes (the VPL method's "indirect", correlated sampling's "lambda").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <glint/core/image.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// An integrator's own layer of the image, by name (the VPL method's "indirect" part,
/// correlated sampling's "lambda").
struct FilmLayer {
    /// The name film users look it up by (Film::layer), e.g. "indirect" or "lambda".
    std::string name;
    /// The layer's values, one per pixel of the image, in the image's size.
    Image<Rgb<float>> pixels;
    bool grey = false;  ///< one value per pixel, in all three bands
};

/// A film policy: what the renderer does with each pixel's estimate. resize(width, height)
/// comes first; then set_pixel(x, y, mean, variance of the mean) once per pixel, from the
/// thread that rendered it (pixels are disjoint: a film that stores per pixel needs no lock);
/// after all pixels, the integrator's finish(film, states) sees the same film.
template <class F, class T>
concept FilmPolicy = Scalar<T> && requires(F& film, int x, const Rgb<T>& value) {
    film.resize(x, x);
    film.set_pixel(x, x, value, value);
};

/// The renderer's default film: the image's layers.
struct Film {
    Image<Rgb<float>> image;     ///< mean radiance per pixel
    Image<Rgb<float>> variance;  ///< variance of that mean (sample variance / spp)
    std::vector<FilmLayer> layers;  ///< what integrators add in finish()

    /// Makes image and variance width x height pixels of zero and drops all layers.
    void resize(int width, int height) {
        image = Image<Rgb<float>>(width, height);
        variance = Image<Rgb<float>>(width, height);
        layers.clear();
    }
    /// The layer called `name`, or null.
    const FilmLayer* layer(const std::string& name) const {
        for (const FilmLayer& l : layers)
            if (l.name == name) return &l;
        return nullptr;
    }
    /// Stores pixel (x, y)'s mean radiance and the variance of that mean, rounded to float.
    /// (x, y) must lie inside the size of the last resize(); it is not checked.
    template <Scalar T>
    void set_pixel(int x, int y, const Rgb<T>& mean, const Rgb<T>& variance_of_mean) {
        for (std::size_t c = 0; c < 3; ++c) {
            image.at(x, y)[c] = float(mean[c]);
            variance.at(x, y)[c] = float(variance_of_mean[c]);
        }
    }
};

}  // namespace glint
