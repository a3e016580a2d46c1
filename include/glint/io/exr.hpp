// glint/io/exr.hpp: OpenEXR output and input of RGB float images.
//
// Needs OpenEXR 3 (Debian libopenexr-dev): link OpenEXR::OpenEXR. write_exr stores the RGB
// image as 32-bit float channels R, G, B, plus optional named layers
// ("variance.R", "lambda.Y", ...) in the same file, ZIP compressed. read_exr_rgb loads the
// R, G, B channels of any EXR (missing channels read as 0), after checking the size its
// header declares against ExrLimits and the file's size (an untrusted header must not make it
// allocate gigabytes).
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <Iex.h>

#include <glint/core/error.hpp>
#include <glint/core/image.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// An extra EXR layer: one channel per name in `channels`, taken from consecutive floats of
/// each pixel of `data` (data.size() == width * height * channels.size()).
struct ExrLayer {
    std::string name;                   // e.g. "variance"
    std::vector<std::string> channels;  // e.g. {"R", "G", "B"} or {"Y"}
    std::vector<float> data;
};

/// Writes `rgb` (and `layers`) to `path`. Throws glint::Error naming the file on failure.
inline void write_exr(const std::string& path, const Image<Rgb<float>>& rgb,
                      const std::vector<ExrLayer>& layers = {}) {
    const std::size_t n = rgb.size();
    for (const auto& l : layers)
        if (l.data.size() != n * l.channels.size())
            throw Error("write_exr(" + path + "): layer '" + l.name + "' has " + std::to_string(l.data.size()) +
                        " floats, expected " + std::to_string(n * l.channels.size()));
    try {
        Imf::Header header(rgb.width, rgb.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        Imf::FrameBuffer fb;
        auto* base = reinterpret_cast<char*>(const_cast<Rgb<float>*>(rgb.pixels.data()));
        const std::size_t xs = sizeof(Rgb<float>), ys = xs * std::size_t(rgb.width);
        const char* names[3] = {"R", "G", "B"};
        for (std::size_t c = 0; c < 3; ++c) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
            fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
        }
        for (const auto& l : layers) {
            const std::size_t k = l.channels.size();
            auto* lb = reinterpret_cast<char*>(const_cast<float*>(l.data.data()));
            for (std::size_t c = 0; c < k; ++c) {
                const std::string name = l.name + "." + l.channels[c];
                header.channels().insert(name, Imf::Channel(Imf::FLOAT));
                fb.insert(name, Imf::Slice(Imf::FLOAT, lb + c * sizeof(float), k * sizeof(float),
                                           k * sizeof(float) * std::size_t(rgb.width)));
            }
        }
        Imf::OutputFile file(path.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(rgb.height);
    } catch (const std::exception& e) {
        throw Error("write_exr(" + path + "): " + e.what());
    }
}

/// Limits read_exr_rgb checks the header against before it allocates: the declared size
/// comes from an untrusted file. A file cannot hold more pixel data than its size times the
/// best ratio of OpenEXR's lossless compressors (zlib's is about 1032:1; the default bound is
/// looser, for headroom).
struct ExrLimits {
    std::uint64_t max_pixels = std::uint64_t(1) << 28;  // 268M pixels: 3.2 GB as RGB float
    double max_compression_ratio = 4096.0;
};

namespace detail {

/// Throws glint::Error unless the data window of `header` is a sane size for a file of
/// `file_bytes` bytes under `limits`.
inline void check_exr_size(const std::string& path, const Imf::Header& header, std::uint64_t file_bytes,
                           const ExrLimits& limits) {
    const Imath::Box2i dw = header.dataWindow();
    const std::int64_t w = std::int64_t(dw.max.x) - dw.min.x + 1, h = std::int64_t(dw.max.y) - dw.min.y + 1;
    const std::string size = std::to_string(w) + " x " + std::to_string(h);
    if (w <= 0 || h <= 0) throw Error("read_exr_rgb(" + path + "): the data window is empty (" + size + ")");
    const std::uint64_t pixels = std::uint64_t(w) * std::uint64_t(h);
    if (pixels > limits.max_pixels)
        throw Error("read_exr_rgb(" + path + "): declares " + size + " pixels, above the limit of " +
                    std::to_string(limits.max_pixels) + " (ExrLimits::max_pixels)");
    double bytes_per_pixel = 0;
    for (auto c = header.channels().begin(); c != header.channels().end(); ++c)
        bytes_per_pixel += (c.channel().type == Imf::HALF ? 2.0 : 4.0) /
                           (double(std::max(1, c.channel().xSampling)) * double(std::max(1, c.channel().ySampling)));
    const double declared = double(pixels) * bytes_per_pixel;
    if (declared > double(file_bytes) * limits.max_compression_ratio)
        throw Error("read_exr_rgb(" + path + "): declares " + size + " pixels (" + std::to_string(declared) +
                    " bytes of samples), more than a file of " + std::to_string(file_bytes) +
                    " bytes can hold (ExrLimits::max_compression_ratio)");
}

}  // namespace detail

/// Reads the R, G, B channels of an EXR file as float. The declared size is checked against
/// `limits` and the file's size before anything is allocated.
inline Image<Rgb<float>> read_exr_rgb(const std::string& path, const ExrLimits& limits = {}) {
    try {
        std::error_code ec;
        const std::uintmax_t file_bytes = std::filesystem::file_size(path, ec);
        if (ec) throw Error("read_exr_rgb(" + path + "): cannot read the file (" + ec.message() + ")");
        Imf::InputFile file(path.c_str());
        detail::check_exr_size(path, file.header(), file_bytes, limits);
        const Imath::Box2i dw = file.header().dataWindow();
        const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
        Image<Rgb<float>> img(w, h);
        Imf::FrameBuffer fb;
        const std::size_t xs = sizeof(Rgb<float>), ys = xs * std::size_t(w);
        char* base = reinterpret_cast<char*>(img.pixels.data()) -
                     (std::ptrdiff_t(dw.min.x) * std::ptrdiff_t(xs) + std::ptrdiff_t(dw.min.y) * std::ptrdiff_t(ys));
        const char* names[3] = {"R", "G", "B"};
        for (std::size_t c = 0; c < 3; ++c)
            fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys, 1, 1, 0.0));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        return img;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error("read_exr_rgb(" + path + "): " + e.what());
    }
}

}  // namespace glint
