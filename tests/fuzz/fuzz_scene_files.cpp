// libFuzzer target: the scene-file readers on fuzzed input. Every input goes to
// parse_scene_json (glint's scene JSON) and, written to a file, to load_gltf: as .glb when it
// starts with the GLB magic "glTF", else as .gltf. A glint::Error is a correct answer to bad
// input; anything else (a crash, a sanitizer report, another exception, a loaded scene with a
// non-finite vertex or an inconsistent triangle table) is a finding.
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include <glint/io/gltf.hpp>
#include <glint/io/scene_json_read.hpp>

namespace {

std::string scratch() {
    static const std::string dir = [] {
        const std::string d = (std::filesystem::temp_directory_path() / ("glint_fuzz_scene_" + std::to_string(getpid()))).string();
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

void check(const glint::Scene<float>& s) {
    if (s.material_of.size() != s.triangles.size() || s.light_of.size() != s.triangles.size()) std::abort();
    for (std::size_t i = 0; i < s.triangles.size(); ++i) {
        for (const auto& p : s.triangles[i])
            if (!glint::all_finite(p)) std::abort();
        if (s.material_of[i] >= s.materials.size()) std::abort();
        if (s.light_of[i] >= std::int32_t(s.area_lights.size())) std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string in(reinterpret_cast<const char*>(data), size);
    try {
        check(glint::parse_scene_json<float>(in, "fuzz.json").scene);
    } catch (const glint::Error&) {
    }
    const std::string path = scratch() + (in.rfind("glTF", 0) == 0 ? "/scene.glb" : "/scene.gltf");
    std::ofstream(path, std::ios::binary) << in;
    try {
        check(glint::load_gltf<float>(path));
    } catch (const glint::Error&) {
    }
    return 0;
}
