// glint/io/exr.hpp: OpenEXR output and input of float images with layers and attributes.
//
// Needs OpenEXR 3 (Debian libopenexr-dev): link OpenEXR::OpenEXR. write_exr stores the RGB
// image as 32-bit float channels R, G, B, plus optional named layers
// ("variance.R", "lambda.Y", "normal.X", ...) and header attributes (int, double or string:
// "glint:spp", ...) in the same file, ZIP compressed unless asked otherwise. read_exr_rgb loads
// the R, G, B channels of any EXR (missing channels read as 0); read_exr_channels loads every
// channel and the int, double and string attributes. Both check the size the header declares
// against ExrLimits and the file's size first (an untrusted header must not make them
// allocate gigabytes).
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <system_error>
#include <variant>
#include <vector>

#include <ImfChannelList.h>
#include <ImfDoubleAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <Iex.h>

#include <glint/core/error.hpp>
#include <glint/core/image.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// An extra EXR layer: one channel per name in `channels`, taken from consecutive floats of
/// each pixel of `data` (data.size() == width * height * channels.size()).
struct ExrLayer {
    std::string name;                   ///< Layer name, prefixed to its channels, e.g. "variance".
    std::vector<std::string> channels;  ///< Channel names within the layer, e.g. {"R", "G", "B"} or {"Y"}.
    std::vector<float> data;  ///< Interleaved pixel values, row by row from the top, channels.size() floats per pixel.
};

/// A header attribute: an int, a double or a string, by name (e.g. "glint:spp").
struct ExrAttribute {
    std::string name;                              ///< Attribute name as stored in the header.
    std::variant<int, double, std::string> value;  ///< Value; its alternative selects the EXR attribute type (int, double, string).
};

/// How write_exr compresses: ZIP (glint's default: zlib over 16 lines), PIZ (wavelet and
/// Huffman coding, OpenEXR's own default) or none; all lossless.
enum class ExrCompression { zip, piz, none };

namespace detail {

inline void add_exr_attribute(Imf::Header& header, const ExrAttribute& a) {
    if (const int* i = std::get_if<int>(&a.value)) header.insert(a.name, Imf::IntAttribute(*i));
    else if (const double* d = std::get_if<double>(&a.value)) header.insert(a.name, Imf::DoubleAttribute(*d));
    else header.insert(a.name, Imf::StringAttribute(std::get<std::string>(a.value)));
}

}  // namespace detail

/// Writes `rgb` (and `layers`, and `attributes` in the header) to `path`. Throws glint::Error
/// naming the file on failure.
inline void write_exr(const std::string& path, const Image<Rgb<float>>& rgb, const std::vector<ExrLayer>& layers = {},
                      const std::vector<ExrAttribute>& attributes = {},
                      ExrCompression compression = ExrCompression::zip) {
    const std::size_t n = rgb.size();
    for (const auto& l : layers)
        if (l.data.size() != n * l.channels.size())
            throw Error("write_exr(" + path + "): layer '" + l.name + "' has " + std::to_string(l.data.size()) +
                        " floats, expected " + std::to_string(n * l.channels.size()));
    try {
        Imf::Header header(rgb.width, rgb.height);
        header.compression() = compression == ExrCompression::zip   ? Imf::ZIP_COMPRESSION
                               : compression == ExrCompression::piz ? Imf::PIZ_COMPRESSION
                                                                    : Imf::NO_COMPRESSION;
        for (const ExrAttribute& a : attributes) detail::add_exr_attribute(header, a);
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
    std::uint64_t max_pixels = std::uint64_t(1) << 28;  ///< Most pixels (width * height) a header may declare; default 2^28, 3.2 GB as RGB float.
    double max_compression_ratio = 4096.0;  ///< Largest accepted ratio of the declared pixel data (bytes, by channel type) to the file size.
};

namespace detail {

/// Throws glint::Error unless the data window of `header` is a sane size for a file of
/// `file_bytes` bytes under `limits`.
inline void check_exr_size(const std::string& path, const Imf::Header& header, std::uint64_t file_bytes,
                           const ExrLimits& limits, const std::string& reader = "read_exr_rgb") {
    const Imath::Box2i dw = header.dataWindow();
    const std::int64_t w = std::int64_t(dw.max.x) - dw.min.x + 1, h = std::int64_t(dw.max.y) - dw.min.y + 1;
    const std::string size = std::to_string(w) + " x " + std::to_string(h);
    if (w <= 0 || h <= 0) throw Error(reader + "(" + path + "): the data window is empty (" + size + ")");
    const std::uint64_t pixels = std::uint64_t(w) * std::uint64_t(h);
    if (pixels > limits.max_pixels)
        throw Error(reader + "(" + path + "): declares " + size + " pixels, above the limit of " +
                    std::to_string(limits.max_pixels) + " (ExrLimits::max_pixels)");
    double bytes_per_pixel = 0;
    for (auto c = header.channels().begin(); c != header.channels().end(); ++c)
        bytes_per_pixel += (c.channel().type == Imf::HALF ? 2.0 : 4.0) /
                           (double(std::max(1, c.channel().xSampling)) * double(std::max(1, c.channel().ySampling)));
    const double declared = double(pixels) * bytes_per_pixel;
    if (declared > double(file_bytes) * limits.max_compression_ratio)
        throw Error(reader + "(" + path + "): declares " + size + " pixels (" + std::to_string(declared) +
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

/// Every float channel of an EXR file (half and uint channels converted), by name, row by
/// row, and the header's int, double and string attributes.
struct ExrChannels {
    /// Image width in pixels (data window).
    int width = 0, height = 0;  ///< Image height in pixels (data window).
    std::map<std::string, std::vector<float>> channels;  ///< Full channel name -> width * height floats, row by row from the top.
    std::vector<ExrAttribute> attributes;  ///< The header's int, double and string attributes; other types are skipped.

    /// The channel called `name`; throws glint::Error naming it and the file's channels.
    const std::vector<float>& channel(const std::string& name) const {
        if (const auto it = channels.find(name); it != channels.end()) return it->second;
        std::string known;
        for (const auto& [k, v] : channels) known += (known.empty() ? "" : ", ") + k;
        throw Error("EXR has no channel '" + name + "' (it has " + known + ")");
    }
    /// The attribute called `name`, or null.
    const ExrAttribute* attribute(const std::string& name) const {
        for (const ExrAttribute& a : attributes)
            if (a.name == name) return &a;
        return nullptr;
    }
};

/// Reads every channel and the int, double and string attributes of an EXR file. The
/// declared size is checked against `limits` and the file's size before anything is allocated.
inline ExrChannels read_exr_channels(const std::string& path, const ExrLimits& limits = {}) {
    try {
        std::error_code ec;
        const std::uintmax_t file_bytes = std::filesystem::file_size(path, ec);
        if (ec) throw Error("read_exr_channels(" + path + "): cannot read the file (" + ec.message() + ")");
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        detail::check_exr_size(path, header, file_bytes, limits, "read_exr_channels");
        const Imath::Box2i dw = header.dataWindow();
        ExrChannels out;
        out.width = dw.max.x - dw.min.x + 1;
        out.height = dw.max.y - dw.min.y + 1;
        const std::size_t w = std::size_t(out.width), n = w * std::size_t(out.height);
        Imf::FrameBuffer fb;
        for (auto c = header.channels().begin(); c != header.channels().end(); ++c) {
            std::vector<float>& v = out.channels[c.name()];
            v.assign(n, 0.0f);
            char* base = reinterpret_cast<char*>(v.data()) -
                         (std::ptrdiff_t(dw.min.x) + std::ptrdiff_t(dw.min.y) * std::ptrdiff_t(w)) * std::ptrdiff_t(sizeof(float));
            fb.insert(c.name(), Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * w, 1, 1, 0.0));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        for (auto a = header.begin(); a != header.end(); ++a) {
            if (const auto* i = dynamic_cast<const Imf::IntAttribute*>(&a.attribute()))
                out.attributes.push_back({a.name(), i->value()});
            else if (const auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&a.attribute()))
                out.attributes.push_back({a.name(), d->value()});
            else if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&a.attribute()))
                out.attributes.push_back({a.name(), s->value()});
        }
        return out;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error("read_exr_channels(" + path + "): " + e.what());
    }
}

}  // namespace glint
