// exr_stats FILE.exr [OUT.exr zip|piz|none]: each channel of an EXR file with its minimum,
// maximum, mean, count of non-zero values and a hash of its bits, and the header's int,
// double and string attributes, read by io/exr.hpp; with OUT, the same channels and attributes written again
// with that compression by OpenEXR (what tools/exr.py's PIZ test reads). What the
// command-line tests (render_obj, glint-render --aov and --scene-file) check their files with.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <string>
#include <type_traits>
#include <vector>
#include <variant>

#include <glint/io/exr.hpp>

/// Writes the channels of `exr` to `path`: R, G, B as the image, every other channel
/// "layer.C" as a layer of its own.
void rewrite(const glint::ExrChannels& exr, const std::string& path, const std::string& how) {
    const glint::ExrCompression compression = how == "piz"    ? glint::ExrCompression::piz
                                              : how == "none" ? glint::ExrCompression::none
                                                              : glint::ExrCompression::zip;
    glint::Image<glint::Rgb<float>> rgb(exr.width, exr.height);
    std::vector<glint::ExrLayer> layers;
    for (const auto& [name, v] : exr.channels) {
        const auto dot = name.rfind('.');
        if (dot == std::string::npos && name.size() == 1 && std::string("RGB").find(name) != std::string::npos) {
            for (std::size_t i = 0; i < v.size(); ++i) rgb.pixels[i][std::string("RGB").find(name)] = v[i];
            continue;
        }
        if (dot == std::string::npos) throw glint::Error("cannot rewrite channel '" + name + "' (not R, G, B or LAYER.C)");
        layers.push_back({name.substr(0, dot), {name.substr(dot + 1)}, v});
    }
    glint::write_exr(path, rgb, layers, exr.attributes, compression);
}

int main(int argc, char** argv) try {
    if (argc != 2 && argc != 4) {
        std::fprintf(stderr, "usage: exr_stats FILE.exr [OUT.exr zip|piz|none]\n");
        return 2;
    }
    const glint::ExrChannels exr = glint::read_exr_channels(argv[1]);
    std::printf("%d x %d\n", exr.width, exr.height);
    for (const auto& [name, v] : exr.channels) {
        double sum = 0;
        std::size_t nonzero = 0;
        std::uint64_t hash = 0xcbf29ce484222325u;  // FNV-1a over the floats' bits: equal only if every value is
        for (float x : v) {
            sum += x;
            nonzero += x != 0.0f;
            hash = (hash ^ std::bit_cast<std::uint32_t>(x)) * 0x100000001b3u;
        }
        const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
        std::printf("channel %s min %g max %g mean %g nonzero %zu hash %016llx\n", name.c_str(), double(*lo), double(*hi),
                    sum / double(v.size()), nonzero, (unsigned long long)hash);
    }
    for (const glint::ExrAttribute& a : exr.attributes)
        std::visit([&](const auto& x) {
            if constexpr (std::is_same_v<std::decay_t<decltype(x)>, std::string>) std::printf("attribute %s = %s\n", a.name.c_str(), x.c_str());
            else std::printf("attribute %s = %g\n", a.name.c_str(), double(x));
        }, a.value);
    if (argc == 4) rewrite(exr, argv[2], argv[3]);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "exr_stats: %s\n", e.what());
    return 1;
}
