// glint/tracer/texture.hpp: an RGB image over texture coordinates, the base-colour texture a
// material's diffuse reflectance is multiplied by (Scene::material_at).
//
//   Texture<float> t = Texture<float>::from_srgb(width, height, 3, 8, bytes);  // rows top first
//   Rgb<float> kd = t.lookup(Vec2<float>(0.25f, 0.75f));
//
// Coordinates follow glTF 2.0 (§3.8.4): (0, 0) is the image's first texel (its top-left
// corner as stored), u runs along a row, v down the rows; a texel's centre sits at
// ((i + 1/2) / width, (j + 1/2) / height). Outside [0, 1] the wrap mode repeats, mirrors or
// clamps. `linear` filtering blends the four nearest texel centres (bilinear); `nearest`
// takes the texel the point falls in. Stored texels are linear reflectances in [0, 1]: 8- and
// 16-bit colour images are decoded from sRGB by its transfer curve (IEC 61966-2-1).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// How coordinates outside [0, 1] map into the image (glTF 2.0's sampler wrap modes).
enum class TextureWrap : std::uint8_t { repeat, mirrored_repeat, clamp };

/// The sRGB transfer curve's inverse: an encoded value in [0, 1] as linear light.
template <Scalar T>
T srgb_to_linear(T c) {
    return c <= T(0.04045) ? c / T(12.92) : std::pow((c + T(0.055)) / T(1.055), T(2.4));
}

/// An RGB texture: linear texels in rows (row 0 at v = 0), a filter and a wrap mode per axis.
template <Scalar T>
struct Texture {
    int width = 0;               ///< Texels per row, > 0.
    int height = 0;              ///< Rows, > 0.
    std::vector<Rgb<T>> texels;  ///< width * height linear reflectances, row after row.
    bool nearest = false;        ///< true: the texel the point falls in; false: bilinear.
    TextureWrap wrap_u = TextureWrap::repeat;  ///< How u outside [0, 1] maps into a row.
    TextureWrap wrap_v = TextureWrap::repeat;  ///< How v outside [0, 1] maps into the rows.
    std::string source;  ///< Where it was read from (messages); empty for a texture made in code.

    /// A texture of sRGB-encoded texels of `bits` (8 or 16, little endian) per channel and
    /// `channels` (1 to 4; grey is copied to every band, alpha ignored) per texel, rows top
    /// first, decoded to linear.
    static Texture from_srgb(int width, int height, int channels, int bits, std::span<const std::uint8_t> bytes) {
        Texture t;
        t.width = width, t.height = height;
        const std::size_t bytes_per = std::size_t(channels) * std::size_t(bits / 8);
        if (width <= 0 || height <= 0 || channels < 1 || channels > 4 || (bits != 8 && bits != 16) ||
            bytes.size() != std::size_t(width) * std::size_t(height) * bytes_per)
            throw Error("Texture::from_srgb: " + std::to_string(width) + " x " + std::to_string(height) + " texels of " +
                        std::to_string(channels) + " channels of " + std::to_string(bits) + " bits do not match " +
                        std::to_string(bytes.size()) + " bytes");
        T table[256];
        for (int k = 0; k < 256; ++k) table[k] = srgb_to_linear(T(k) / T(255));
        const auto channel = [&](const std::uint8_t* p, int c) {
            if (bits == 8) return table[p[c]];
            return srgb_to_linear(T(unsigned(p[2 * c]) | unsigned(p[2 * c + 1]) << 8) / T(65535));
        };
        t.texels.resize(std::size_t(width) * std::size_t(height));
        for (std::size_t i = 0; i < t.texels.size(); ++i) {
            const std::uint8_t* p = bytes.data() + i * bytes_per;
            t.texels[i] = channels < 3 ? Rgb<T>(channel(p, 0)) : Rgb<T>(channel(p, 0), channel(p, 1), channel(p, 2));
        }
        return t;
    }

    /// Throws glint::Error naming `what` unless the size matches the texels and every texel
    /// lies in [0, 1].
    void validate(const std::string& what) const {
        if (width <= 0 || height <= 0 || texels.size() != std::size_t(width) * std::size_t(height))
            throw Error(what + ": " + std::to_string(texels.size()) + " texels for " + std::to_string(width) + " x " +
                        std::to_string(height));
        for (std::size_t i = 0; i < texels.size(); ++i)
            if (!texels[i].is_finite() || texels[i].min() < T(0) || texels[i].max() > T(1))
                throw Error(what + ": texel " + std::to_string(i) + " is outside [0, 1]");
    }

    /// Whether every texel has equal bands.
    bool grey() const {
        for (const Rgb<T>& c : texels)
            if (c[0] != c[1] || c[1] != c[2]) return false;
        return true;
    }

    /// The mean texel.
    Rgb<T> mean() const {
        Rgb<T> sum(T(0));
        for (const Rgb<T>& c : texels) sum += c;
        return texels.empty() ? sum : sum / T(texels.size());
    }

    /// The filtered texture at coordinates uv.
    Rgb<T> lookup(const Vec2<T>& uv) const {
        const T x = uv.x * T(width), y = uv.y * T(height);
        if (nearest) return at(index(x), index(y));
        const T fx = x - T(0.5), fy = y - T(0.5);
        const T x0 = std::floor(fx), y0 = std::floor(fy);
        const T ax = fx - x0, ay = fy - y0;
        const int i = index(x0), j = index(y0);
        return (at(i, j) * (T(1) - ax) + at(i + 1, j) * ax) * (T(1) - ay) +
               (at(i, j + 1) * (T(1) - ax) + at(i + 1, j + 1) * ax) * ay;
    }

private:
    // A texel index from a coordinate, held to +-2^24 texels (where a float's unit ends) so
    // that the conversion is defined for any finite coordinate.
    static int index(T x) { return int(std::clamp(std::floor(x), T(-16777216), T(16777216))); }
    static int wrapped(int i, int n, TextureWrap mode) {
        switch (mode) {
        case TextureWrap::clamp: return i < 0 ? 0 : i >= n ? n - 1 : i;
        case TextureWrap::mirrored_repeat: {
            const int period = ((i % (2 * n)) + 2 * n) % (2 * n);
            return period < n ? period : 2 * n - 1 - period;
        }
        default: return ((i % n) + n) % n;
        }
    }
    const Rgb<T>& at(int i, int j) const {
        return texels[std::size_t(wrapped(j, height, wrap_v)) * std::size_t(width) + std::size_t(wrapped(i, width, wrap_u))];
    }
};

}  // namespace glint
