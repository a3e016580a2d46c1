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
    int width = 0;
    int height = 0;
    std::vector<Pixel> pixels;

    Image() = default;
    Image(int w, int h, const Pixel& fill = Pixel{}) : width(w), height(h) {
        if (w <= 0 || h <= 0)
            throw Error("glint::Image: size " + std::to_string(w) + "x" + std::to_string(h) +
                        " must be positive");
        pixels.assign(std::size_t(w) * std::size_t(h), fill);
    }

    Pixel& at(int x, int y) { return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
    const Pixel& at(int x, int y) const {
        return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)];
    }
    std::size_t size() const { return pixels.size(); }
};

}  // namespace glint
