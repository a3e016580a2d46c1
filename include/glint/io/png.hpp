// glint/io/png.hpp: an 8-bit sRGB PNG preview of a linear RGB image.
//
// Tone mapping: multiply by 2^exposure, map each channel x to x / (1 + x) only where
// `reinhard` is set (else clamp to [0, 1]), then the sRGB transfer curve.
//
// Needs stb_image_write (Debian libstb-dev, header only), included as <stb_image_write.h>:
// the glint::io target (and the glint-io pkg-config file) puts stb's folder on the include
// path. stb's implementation is not compiled by this header: define GLINT_STB_IMPLEMENTATION
// in exactly one translation unit of the program before including this header (it defines
// STB_IMAGE_WRITE_IMPLEMENTATION there), or link the stb_image_write implementation the
// program already has.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/image.hpp>
#include <glint/core/spectrum.hpp>

#if defined(GLINT_STB_IMPLEMENTATION) && !defined(STB_IMAGE_WRITE_IMPLEMENTATION)
#define STB_IMAGE_WRITE_IMPLEMENTATION
#endif
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wdouble-promotion"
#endif
#include <stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace glint {

/// Linear value to an 8-bit sRGB code.
inline std::uint8_t to_srgb8(float linear) {
    const float x = std::clamp(linear, 0.0f, 1.0f);
    const float s = x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
    return static_cast<std::uint8_t>(std::lround(s * 255.0f));
}

/// Writes a tone-mapped PNG preview. NaN pixels are written magenta so they are seen.
inline void write_png(const std::string& path, const Image<Rgb<float>>& img, float exposure = 0.0f,
                      bool reinhard = false) {
    std::vector<std::uint8_t> bytes(img.size() * 3);
    const float scale = std::exp2(exposure);
    for (std::size_t i = 0; i < img.size(); ++i) {
        const Rgb<float>& p = img.pixels[i];
        const bool bad = !p.is_finite();
        for (int c = 0; c < 3; ++c) {
            float v = p[std::size_t(c)] * scale;
            if (reinhard) v = v / (1.0f + v);
            bytes[3 * i + std::size_t(c)] = bad ? (c == 1 ? 0 : 255) : to_srgb8(v);
        }
    }
    if (!stbi_write_png(path.c_str(), img.width, img.height, 3, bytes.data(), img.width * 3))
        throw Error("write_png(" + path + "): cannot write the file");
}

}  // namespace glint
