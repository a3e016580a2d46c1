// exr_stats FILE.exr: each channel of an EXR file with its minimum, maximum, mean and count of
// non-zero values, and the header's int, double and string attributes, read by io/exr.hpp.
// What the command-line tests (render_obj, glint-render --aov) check their files with.
#include <algorithm>
#include <cstdio>
#include <variant>

#include <glint/io/exr.hpp>

int main(int argc, char** argv) try {
    if (argc != 2) {
        std::fprintf(stderr, "usage: exr_stats FILE.exr\n");
        return 2;
    }
    const glint::ExrChannels exr = glint::read_exr_channels(argv[1]);
    std::printf("%d x %d\n", exr.width, exr.height);
    for (const auto& [name, v] : exr.channels) {
        double sum = 0;
        std::size_t nonzero = 0;
        for (float x : v) {
            sum += x;
            nonzero += x != 0.0f;
        }
        const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
        std::printf("channel %s min %g max %g mean %g nonzero %zu\n", name.c_str(), double(*lo), double(*hi),
                    sum / double(v.size()), nonzero);
    }
    for (const glint::ExrAttribute& a : exr.attributes)
        std::visit([&](const auto& x) {
            if constexpr (std::is_same_v<std::decay_t<decltype(x)>, std::string>) std::printf("attribute %s = %s\n", a.name.c_str(), x.c_str());
            else std::printf("attribute %s = %g\n", a.name.c_str(), double(x));
        }, a.value);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "exr_stats: %s\n", e.what());
    return 1;
}
