// Built against the *installed* glint package with the io component (glint::io): every io
// header, stb's implementation opted into here, one write/read round trip each.
#include <cstdio>
#include <fstream>

#define GLINT_STB_IMPLEMENTATION
#include <glint/io/exr.hpp>
#include <glint/io/obj.hpp>
#include <glint/io/png.hpp>
#include <glint/io/scene_json.hpp>

int main() {
    glint::Image<glint::Rgb<float>> img(4, 2);
    img.at(1, 1) = glint::Rgb<float>(0.5f, 0.25f, 1.0f);
    glint::write_exr("consumer_io.exr", img);
    glint::write_png("consumer_io.png", img);
    std::ofstream("consumer_io.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    const bool ok = glint::read_exr_rgb("consumer_io.exr").at(1, 1) == img.at(1, 1) &&
                    glint::load_obj("consumer_io.obj").triangles.size() == 1;
    std::printf("consumer_io: installed glint::io %s\n", ok ? "works" : "FAILED");
    return ok ? 0 : 1;
}
