// libFuzzer target: load_obj on fuzzed OBJ and MTL text. The input is split at the first
// "\n@@\n" into the OBJ text and the MTL text (scene.mtl beside it). A glint::Error is a
// correct answer to bad input; anything else (a crash, a sanitizer report, another
// exception, a mesh with a non-finite vertex) is a finding.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include <glint/io/obj.hpp>

namespace {
std::string scratch() {
    static const std::string dir = [] {
        const std::string d = (std::filesystem::temp_directory_path() / ("glint_fuzz_obj_" + std::to_string(getpid()))).string();
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string in(reinterpret_cast<const char*>(data), size);
    const auto cut = in.find("\n@@\n");
    const std::string obj = in.substr(0, cut), mtl = cut == std::string::npos ? "" : in.substr(cut + 4);
    const std::string dir = scratch();
    std::ofstream(dir + "/scene.obj", std::ios::binary) << obj;
    std::ofstream(dir + "/scene.mtl", std::ios::binary) << mtl;
    try {
        const glint::ObjMesh m = glint::load_obj(dir + "/scene.obj");
        for (const auto& t : m.triangles)
            for (const auto& p : t)
                if (!glint::all_finite(p)) std::abort();
        for (const auto& mat : m.materials)
            if (!(mat.kd.min() >= 0.0f && mat.kd.max() <= 1.0f && mat.ke.min() >= 0.0f && mat.ke.is_finite())) std::abort();
        if (m.material.size() != m.triangles.size() || m.line.size() != m.triangles.size()) std::abort();
    } catch (const glint::Error&) {
    }
    return 0;
}
