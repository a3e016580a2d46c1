// Built against the *installed* glint package with the io component (glint::io): every io
// header, stb's implementation opted into here, one write/read round trip each.
#include <cstdio>
#include <fstream>

#define GLINT_STB_IMPLEMENTATION
#include <glint/io/exr.hpp>
#include <glint/io/gltf.hpp>
#include <glint/io/obj.hpp>
#include <glint/io/png.hpp>
#include <glint/io/scene_json.hpp>
#include <glint/io/scene_json_read.hpp>

int main() {
    glint::Image<glint::Rgb<float>> img(4, 2);
    img.at(1, 1) = glint::Rgb<float>(0.5f, 0.25f, 1.0f);
    glint::write_exr("consumer_io.exr", img);
    glint::write_png("consumer_io.png", img);
    std::ofstream("consumer_io.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    // A one-triangle glTF, its buffer a base64 data URI (three float positions).
    std::ofstream("consumer_io.gltf")
        << R"({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
              "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
              "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,)"
           "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"
        << R"("}], "bufferViews": [{"buffer": 0, "byteLength": 36}],
              "accessors": [{"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 3}]})";
    const glint::Scene<float> gltf = glint::load_gltf<float>("consumer_io.gltf");
    glint::write_scene_json("consumer_io.json", gltf, glint::SceneJsonView{});
    const bool ok = glint::read_exr_rgb("consumer_io.exr").at(1, 1) == img.at(1, 1) &&
                    glint::load_obj("consumer_io.obj").triangles.size() == 1 && gltf.triangles.size() == 1 &&
                    glint::read_scene_json<float>("consumer_io.json").scene.triangles == gltf.triangles;
    std::printf("consumer_io: installed glint::io %s\n", ok ? "works" : "FAILED");
    return ok ? 0 : 1;
}
