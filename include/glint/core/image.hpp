// glint/core/image.hpp: a row-major image of any pixel type (RGB spectra, scalars).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <glint/core/error.hpp>

namespace glint {

/// width x height pixels, row-major, (0, 0) at the top left.
template <class Pixel>
struct Image {
    /// Columns (pixels per row); 0 for a default-constructed image.
    int width = 0;
    /// Rows; 0 for a default-constructed image.
    int height = 0;
    /// width * height pixels, row after row from the top: pixel (x, y) is pixels[y * width + x].
    std::vector<Pixel> pixels;

    Image() = default;
    /// A w x h image with every pixel set to `fill`. Throws glint::Error unless w > 0 and h > 0.
    Image(int w, int h, const Pixel& fill = Pixel{}) : width(w), height(h) {
        if (w <= 0 || h <= 0)
            throw Error("glint::Image: size " + std::to_string(w) + "x" + std::to_string(h) +
                        " must be positive");
        pixels.assign(std::size_t(w) * std::size_t(h), fill);
    }

    /// Pixel in column x, row y (row 0 at the top). Unchecked: 0 <= x < width, 0 <= y < height.
    Pixel& at(int x, int y) { return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
    /// Read-only pixel in column x, row y; unchecked like the mutable at().
    const Pixel& at(int x, int y) const {
        return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)];
    }
    /// Pixel count, width * height.
    std::size_t size() const { return pixels.size(); }
};

}  // namespace glint
