// glint/io/exr.hpp: OpenEXR output and input of RGB float images.
//
// Needs OpenEXR 3 (Debian libopenexr-dev): link OpenEXR::OpenEXR. write_exr stores the RGB
// image as 32-bit float channels R, G, B, plus optional named layers
// ("variance.R", "lambda.Y", ...) in the same file, ZIP compressed. read_exr_rgb loads the
// R, G, B channels of any EXR (missing channels read as 0).
#pragma once

#include <string>
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
        for (int c = 0; c < 3; ++c) {
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

/// Reads the R, G, B channels of an EXR file as float.
inline Image<Rgb<float>> read_exr_rgb(const std::string& path) {
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
        Image<Rgb<float>> img(w, h);
        Imf::FrameBuffer fb;
        const std::size_t xs = sizeof(Rgb<float>), ys = xs * std::size_t(w);
        char* base = reinterpret_cast<char*>(img.pixels.data()) -
                     (std::ptrdiff_t(dw.min.x) * std::ptrdiff_t(xs) + std::ptrdiff_t(dw.min.y) * std::ptrdiff_t(ys));
        const char* names[3] = {"R", "G", "B"};
        for (int c = 0; c < 3; ++c)
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
