// libFuzzer target: read_exr_rgb on fuzzed files (limits at 2^20 pixels, so a fuzzed header
// cannot make a run allocate much). A glint::Error is a correct answer; a crash, a sanitizer
// report or an out-of-memory is a finding.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include <glint/io/exr.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::string path =
        (std::filesystem::temp_directory_path() / ("glint_fuzz_" + std::to_string(getpid()) + ".exr")).string();
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), std::streamsize(size));
    glint::ExrLimits limits;
    limits.max_pixels = 1u << 20;
    try {
        const auto img = glint::read_exr_rgb(path, limits);
        if (img.size() > limits.max_pixels) __builtin_trap();
    } catch (const glint::Error&) {
    }
    return 0;
}
