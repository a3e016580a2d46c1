// Tests for glint/io's scene files: a glTF 2.0 scene the test writes itself (a quad under a
// two-level node transform, a camera, a KHR_lights_punctual point light; .gltf with a base64
// buffer and .glb) loads with the right geometry, camera and light and renders the same as
// the scene built in C++ within standard errors, and so does its base-colour texture; the
// material mapping; bad glTF input named by file and item; the scene JSON of --export-scene
// read back exactly.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>
#define GLINT_STB_IMPLEMENTATION  // stb_image_write's functions (the test's PNG textures), compiled in this file

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include <glint/core/random.hpp>
#include <glint/io/exr.hpp>
#include <glint/io/gltf.hpp>
#include <glint/io/json.hpp>
#include <glint/io/obj_scene.hpp>
#include <glint/io/png.hpp>
#include <glint/io/scene_json.hpp>
#include <glint/io/scene_json_read.hpp>
#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/named_render.hpp>
#include "glint_instances.hpp"  // render_named for AnyAccel, compiled once (instances/)
#include <glint/tracer/scenes.hpp>

using namespace glint;

namespace {

std::string temp_path(const std::string& name) {
    return (std::filesystem::temp_directory_path() / ("glint_test_io_" + name)).string();
}

std::string base64(const std::vector<unsigned char>& in) {
    static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (std::size_t i = 0; i < in.size(); i += 3) {
        const std::uint32_t n = std::uint32_t(in[i]) << 16 | (i + 1 < in.size() ? std::uint32_t(in[i + 1]) << 8 : 0u) |
                                (i + 2 < in.size() ? std::uint32_t(in[i + 2]) : 0u);
        out += abc[(n >> 18) & 63];
        out += abc[(n >> 12) & 63];
        out += i + 1 < in.size() ? abc[(n >> 6) & 63] : '=';
        out += i + 2 < in.size() ? abc[n & 63] : '=';
    }
    return out;
}

/// The pieces of the test's glTF: a quad (x, y in [-1, 1], z = 0, counter-clockwise seen
/// from +z) of `material` under node 1 (rotated -90 degrees about x, scaled by 2) under node
/// 0 (moved to y = -1): in the world the floor y = -1, x and z in [-2, 2], facing +y. A
/// camera at (0, 1, 4) looking down -z; a point light of 3415 cd (5 W/sr) at (0, 1, 0).
struct GltfFixture {
    std::vector<float> positions{-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
    std::vector<std::uint16_t> indices{0, 1, 2, 0, 2, 3};
    std::vector<float> normals;  // a NORMAL accessor (2) where not empty, after the indices
    std::vector<float> uvs;      // a TEXCOORD_0 accessor where not empty, after the normals
    int mode = 4;
    std::size_t position_count = 4;  // the POSITION accessor's count
    std::string extra;               // more top-level members, after a comma
    int position_accessor = 0;
    std::string material = R"({"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.6, 0.4, 1], "metallicFactor": 0, "roughnessFactor": 1}})";
    std::string nodes = R"([{"translation": [0, -1, 0], "children": [1]},
        {"mesh": 0, "rotation": [-0.70710678118654752, 0, 0, 0.70710678118654752], "scale": [2, 2, 2]},
        {"camera": 0, "translation": [0, 1, 4]},
        {"translation": [0, 1, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}])";
    std::string lights = R"([{"type": "point", "color": [1, 1, 1], "intensity": 3415}])";

    std::vector<unsigned char> buffer() const {
        std::vector<unsigned char> b(positions.size() * 4 + indices.size() * 2 + normals.size() * 4 + uvs.size() * 4);
        std::memcpy(b.data(), positions.data(), positions.size() * 4);
        std::memcpy(b.data() + positions.size() * 4, indices.data(), indices.size() * 2);
        if (!normals.empty()) std::memcpy(b.data() + positions.size() * 4 + indices.size() * 2, normals.data(), normals.size() * 4);
        if (!uvs.empty())
            std::memcpy(b.data() + positions.size() * 4 + indices.size() * 2 + normals.size() * 4, uvs.data(), uvs.size() * 4);
        return b;
    }

    /// The TEXCOORD_0 attribute, buffer view and accessor (index 2 or 3), where uvs is not empty.
    std::string uv_attribute() const { return uvs.empty() ? "" : ", \"TEXCOORD_0\": " + std::to_string(normals.empty() ? 2 : 3); }
    std::string uv_view() const {
        const std::size_t offset = positions.size() * 4 + indices.size() * 2 + normals.size() * 4;
        return uvs.empty() ? "" : R"(, {"buffer": 0, "byteOffset": )" + std::to_string(offset) + R"(, "byteLength": )" + std::to_string(uvs.size() * 4) + "}";
    }
    std::string uv_accessor() const {
        return uvs.empty() ? "" : R"(, {"bufferView": )" + std::to_string(normals.empty() ? 2 : 3) +
                                      R"(, "componentType": 5126, "type": "VEC2", "count": )" + std::to_string(uvs.size() / 2) + "}";
    }

    /// The JSON; `uri` empty: the buffer is a .glb's BIN chunk.
    std::string json(const std::string& uri) const {
        const std::size_t pb = positions.size() * 4, ib = indices.size() * 2, nb = normals.size() * 4 + uvs.size() * 4;
        std::ostringstream j;
        j << R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 2, 3]}], "nodes": )" << nodes
          << R"(, "meshes": [{"primitives": [{"attributes": {"POSITION": )" << position_accessor
          << (normals.empty() ? "" : R"(, "NORMAL": 2)") << uv_attribute() << R"(}, "indices": 1, "material": 0, "mode": )" << mode
          << R"(}]}], "materials": [)" << material << R"(], "cameras": [{"type": "perspective", "perspective": )"
          << R"({"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.01}}], "extensionsUsed": ["KHR_lights_punctual"], )"
          << R"("extensions": {"KHR_lights_punctual": {"lights": )" << lights << "}}, \"buffers\": [{\"byteLength\": " << pb + ib + nb
          << (uri.empty() ? "" : ", \"uri\": \"" + uri + "\"") << R"(}], "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": )"
          << pb << R"(}, {"buffer": 0, "byteOffset": )" << pb << R"(, "byteLength": )" << ib << "}"
          << (normals.empty() ? "" : R"(, {"buffer": 0, "byteOffset": )" + std::to_string(pb + ib) + R"(, "byteLength": )" + std::to_string(normals.size() * 4) + "}")
          << uv_view()
          << R"(], "accessors": [{"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": )" << position_count
          << R"(}, {"bufferView": 1, "componentType": 5123, "type": "SCALAR", "count": )" << indices.size() << "}"
          << (normals.empty() ? "" : R"(, {"bufferView": 2, "componentType": 5126, "type": "VEC3", "count": )" + std::to_string(normals.size() / 3) + "}")
          << uv_accessor() << "]" << extra << "}";
        return j.str();
    }

    /// Writes name.gltf (buffer as a base64 data URI) and returns its path.
    std::string write_gltf(const std::string& name) const {
        const std::string path = temp_path(name + ".gltf");
        std::ofstream(path) << json("data:application/octet-stream;base64," + base64(buffer()));
        return path;
    }

    /// Writes name.glb (glTF 2.0, §4.4: a 12-byte header, a JSON chunk, a BIN chunk).
    std::string write_glb(const std::string& name) const {
        std::string text = json("");
        while (text.size() % 4) text += ' ';
        std::vector<unsigned char> bin = buffer();
        while (bin.size() % 4) bin.push_back(0);
        const auto u32 = [](std::ofstream& f, std::uint32_t v) { f.write(reinterpret_cast<const char*>(&v), 4); };
        const std::string path = temp_path(name + ".glb");
        std::ofstream f(path, std::ios::binary);
        u32(f, 0x46546C67u), u32(f, 2), u32(f, std::uint32_t(12 + 8 + text.size() + 8 + bin.size()));
        u32(f, std::uint32_t(text.size())), u32(f, 0x4E4F534Au);
        f.write(text.data(), std::streamsize(text.size()));
        u32(f, std::uint32_t(bin.size())), u32(f, 0x004E4942u);
        f.write(reinterpret_cast<const char*>(bin.data()), std::streamsize(bin.size()));
        return path;
    }
};

/// The fixture's scene built in C++ (kd scaled by `kd_scale`).
Scene<float> fixture_scene(float kd_scale = 1.0f) {
    Scene<float> s;
    const auto m = s.add_material(Material<float>::lambertian(Rgb<float>(0.8f, 0.6f, 0.4f) * kd_scale));
    s.add_quad({-2, -1, 2}, {2, -1, 2}, {2, -1, -2}, {-2, -1, -2}, m);
    s.point_lights.push_back(PointLight<float>::isotropic({0, 1, 0}, Rgb<float>(5.0f)));
    s.camera = Camera<float>{{0, 1, 4}, {0, 1, 3}, {0, 1, 0}, 0.8f};
    return s;
}

RenderResult render(const Scene<float>& s, std::uint64_t seed, const std::string& sampler = "random") {
    NamedRender<float> o;
    o.image.width = o.image.height = 24;
    o.image.spp = 16;
    o.image.threads = 1;
    o.sampler = sampler;
    o.seed = seed;
    const DefaultAccel accel(s.triangles);
    return render_named(s, any_accel_view(accel), o);
}

/// The largest |mean_a - mean_b| / its standard error over the bands (independent renders).
double mean_difference_z(const RenderResult& a, const RenderResult& b) {
    const double n = double(a.image.size());
    double z = 0;
    for (std::size_t c = 0; c < 3; ++c) {
        double ma = 0, mb = 0, var = 0;
        for (std::size_t i = 0; i < a.image.size(); ++i) {
            ma += a.image.pixels[i][c] / n;
            mb += b.image.pixels[i][c] / n;
            var += (a.variance.pixels[i][c] + b.variance.pixels[i][c]) / (n * n);
        }
        REQUIRE(ma > 0.0);
        z = std::max(z, std::abs(ma - mb) / std::sqrt(var));
    }
    return z;
}

/// The largest |mean_a - mean_b| / its standard error over the four quadrants of the images
/// and the bands (independent renders; a region black in both counts 0).
double quadrant_difference_z(const RenderResult& a, const RenderResult& b) {
    double z = 0;
    const int w = a.image.width, h = a.image.height;
    for (int q = 0; q < 4; ++q)
        for (std::size_t c = 0; c < 3; ++c) {
            double ma = 0, mb = 0, var = 0;
            for (int y = (q / 2) * h / 2; y < (q / 2 + 1) * h / 2; ++y)
                for (int x = (q % 2) * w / 2; x < (q % 2 + 1) * w / 2; ++x) {
                    ma += a.image.at(x, y)[c], mb += b.image.at(x, y)[c];
                    var += a.variance.at(x, y)[c] + b.variance.at(x, y)[c];
                }
            if (var > 0.0) z = std::max(z, std::abs(ma - mb) / std::sqrt(var));
            else REQUIRE(ma == mb);
        }
    return z;
}

void require_close(const Vec3f& a, const Vec3f& b) {
    INFO(a.x << "," << a.y << "," << a.z << " vs " << b.x << "," << b.y << "," << b.z);
    REQUIRE(glm::length(a - b) < 1e-5f);
}

/// The message load_gltf throws for the fixture, written as a .gltf.
std::string gltf_error(const GltfFixture& f, const std::string& name) {
    try {
        load_gltf<float>(f.write_gltf(name));
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace

TEST_CASE("gltf: the quad, its node transforms, the camera and the point light load as written") {
    const GltfFixture f;
    for (const std::string& path : {f.write_gltf("quad"), f.write_glb("quad")}) {
        INFO(path);
        const GltfScene<float> g = read_gltf<float>(path);
        const Scene<float> want = fixture_scene();
        REQUIRE(g.scene.triangles.size() == 2);
        for (std::size_t t = 0; t < 2; ++t)
            for (std::size_t k = 0; k < 3; ++k) require_close(g.scene.triangles[t][k], want.triangles[t][k]);
        require_close(g.scene.normal(0), {0, 1, 0});
        REQUIRE(g.scene.materials.size() == 1);
        CHECK(g.scene.materials[0].kind == MaterialKind::lambertian);
        CHECK(g.scene.materials[0].kd[1] == doctest::Approx(0.6));
        REQUIRE(g.scene.point_lights.size() == 1);
        require_close(g.scene.point_lights[0].position, {0, 1, 0});
        CHECK(g.scene.point_lights[0].intensity[0] == doctest::Approx(5.0));  // 3415 cd / 683 lm/W
        CHECK(g.has_camera);
        CHECK(g.aspect == doctest::Approx(1.5));
        require_close(g.scene.camera.eye, {0, 1, 4});
        require_close(glm::normalize(g.scene.camera.target - g.scene.camera.eye), {0, 0, -1});
        require_close(g.scene.camera.up, {0, 1, 0});
        CHECK(g.scene.camera.fov_y == doctest::Approx(0.8));
        CHECK(g.warnings.empty());
    }
}

TEST_CASE("gltf: the loaded scene renders as the scene built in C++, within standard errors") {
    const Scene<float> loaded = load_gltf<float>(GltfFixture{}.write_gltf("render"));
    const RenderResult a = render(loaded, 1), b = render(fixture_scene(), 2);
    const double z = mean_difference_z(a, b);
    MESSAGE("glTF against C++: " << z << " standard errors apart");
    CHECK(z < 4.0);
    // The comparison can fail: a 10 % darker floor is told apart.
    const double darker = mean_difference_z(a, render(fixture_scene(0.9f), 2));
    MESSAGE("against a 10 % darker floor: " << darker << " standard errors apart");
    CHECK(darker > 4.0);
}

TEST_CASE("gltf: a mirroring transform keeps the front face; strips and fans are triangles") {
    GltfFixture f;
    f.nodes = R"([{"translation": [0, -1, 0], "children": [1]},
        {"mesh": 0, "matrix": [2,0,0,0, 0,0,-2,0, 0,2,0,0, 0,0,0,1]}, {"camera": 0}, {}])";
    const Scene<float> s = load_gltf<float>(f.write_gltf("matrix"));
    require_close(s.normal(0), {0, 1, 0});  // the matrix (2x, 2z, -2y) maps +z to +y, determinant 8
    f.nodes = R"([{"translation": [0, -1, 0], "children": [1]}, {"mesh": 0, "scale": [1, 1, -1]}, {}, {}])";
    // z -> -z mirrors: the front face, +z in the node's frame, becomes -z, though the
    // positions (z = 0) do not move.
    require_close(load_gltf<float>(f.write_gltf("mirror")).normal(0), {0, 0, -1});
    f = GltfFixture{};
    f.mode = 6;  // a fan 0 1 2 3: (0 1 2), (0 2 3)
    f.indices = {0, 1, 2, 3};
    const Scene<float> fan = load_gltf<float>(f.write_gltf("fan"));
    REQUIRE(fan.triangles.size() == 2);
    require_close(fan.normal(1), {0, 1, 0});
    f.mode = 5;  // a strip 0 1 3 2: (0 1 3), then (3 1 2) in the same orientation
    f.indices = {0, 1, 3, 2};
    const Scene<float> strip = load_gltf<float>(f.write_gltf("strip"));
    REQUIRE(strip.triangles.size() == 2);
    require_close(strip.normal(0), {0, 1, 0});
    require_close(strip.normal(1), {0, 1, 0});
}

TEST_CASE("gltf: metallic-roughness, emission and spot lights map as the header states") {
    GltfFixture f;
    auto material = [&](const std::string& m) {
        f.material = m;
        return load_gltf<float>(f.write_gltf("material")).materials.at(0);
    };
    CHECK(material(R"({"pbrMetallicRoughness": {"metallicFactor": 1, "roughnessFactor": 0.05}})").kind == MaterialKind::mirror);
    const Material<float> metal = material(R"({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "roughnessFactor": 0.5}})");
    CHECK(metal.kind == MaterialKind::glossy);
    CHECK(metal.exponent == doctest::Approx(2.0 / 0.0625 - 2.0));
    CHECK(metal.ks[0] == doctest::Approx(0.5));
    CHECK(metal.kd[0] == doctest::Approx(0.0));
    const Material<float> plastic = material(R"({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.3}})");
    CHECK(plastic.kind == MaterialKind::glossy);
    CHECK(plastic.ks[0] == doctest::Approx(0.04));
    CHECK(material(R"({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_ior": {"ior": 1.33}}})").ior ==
          doctest::Approx(1.33));
    f.material = R"({"emissiveFactor": [1, 0.5, 0.25], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}}})";
    const Scene<float> lamp = load_gltf<float>(f.write_gltf("emissive"));
    CHECK(lamp.area_lights.size() == 2);
    CHECK(lamp.area_lights[0].emission[1] == doctest::Approx(2.0));
    f.material = R"({"emissiveTexture": {"index": 0}, "pbrMetallicRoughness": {"metallicFactor": 0}})";
    const std::array<std::uint8_t, 3> white{255, 255, 255};
    REQUIRE(stbi_write_png(temp_path("white.png").c_str(), 1, 1, 3, white.data(), 3) != 0);
    f.extra = R"(, "textures": [{"source": 0}], "images": [{"uri": "glint_test_io_white.png"}])";
    const GltfScene<float> textured = read_gltf<float>(f.write_gltf("texture"));
    REQUIRE(textured.warnings.size() == 1);
    CHECK(textured.warnings[0].find("material 0 (''): emissive, metallic-roughness and normal textures are ignored") != std::string::npos);
    CHECK(textured.scene.materials.at(0).kind == MaterialKind::lambertian);
    f.lights = R"([{"type": "spot", "intensity": 683, "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.6}}])";
    f.nodes = R"([{"children": [1]}, {"mesh": 0}, {"camera": 0}, {"rotation": [-0.70710678118654752, 0, 0, 0.70710678118654752],
        "extensions": {"KHR_lights_punctual": {"light": 0}}}])";
    const PointLight<float> spot = load_gltf<float>(f.write_gltf("spot")).point_lights.at(0);
    CHECK(spot.kind == PointLightKind::spot);
    require_close(spot.axis, {0, -1, 0});  // -z turned -90 degrees about x
    CHECK(spot.cos_outer == doctest::Approx(std::cos(0.6)));
    CHECK(spot.cos_inner == doctest::Approx(std::cos(0.3)));
    CHECK(spot.intensity[2] == doctest::Approx(1.0));
    f.lights = R"([{"type": "spot", "spot": {"innerConeAngle": 0, "outerConeAngle": 1.5707963267948966}}])";
    CHECK(load_gltf<float>(f.write_gltf("hemisphere_spot")).point_lights.at(0).cos_outer == 0.0f);
}

TEST_CASE("gltf: bad input is an error naming the file and the item") {
    auto contains = [](const std::string& msg, const std::string& part) {
        INFO(msg);
        CHECK(msg.find(part) != std::string::npos);
    };
    try {
        load_gltf<float>(temp_path("no_such_file.gltf"));
        FAIL("no error");
    } catch (const Error& e) {
        contains(e.what(), "no_such_file.gltf");
    }
    GltfFixture f;
    f.mode = 1;  // LINES
    contains(gltf_error(f, "lines"), "mesh 0, primitive 0: primitive mode 1");
    f = GltfFixture{};
    f.positions[7] = std::numeric_limits<float>::quiet_NaN();
    const std::string nan = gltf_error(f, "nan");
    contains(nan, "glint_test_io_nan.gltf");
    contains(nan, "POSITION accessor 0: position 2 is not finite");
    f = GltfFixture{};
    f.indices[4] = 9;
    contains(gltf_error(f, "index"), "indices accessor 1: index 4 = 9 is past the 4 vertices");
    f = GltfFixture{};
    f.position_accessor = 1;
    contains(gltf_error(f, "scalar_positions"), "mesh 0, primitive 0, POSITION accessor 1: expected type VEC3");
    f = GltfFixture{};
    f.position_count = 5;
    contains(gltf_error(f, "past_buffer"), "POSITION accessor 0: 5 elements reach past the end of its buffer");
    f.position_count = std::size_t(1) << 62;  // stride * count overflows
    contains(gltf_error(f, "overflow"), "elements reach past the end of its buffer");
    f = GltfFixture{};
    f.nodes = R"([{"children": [1]}, {"mesh": 0, "children": [0]}, {}, {}])";
    contains(gltf_error(f, "cycle"), "node 0 is its own ancestor");
    f = GltfFixture{};
    f.material = R"({"emissiveFactor": [1, 1, 1]})";
    f.positions = {0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0};
    contains(gltf_error(f, "flat_emitter"), "emissive triangle 0 has zero area");
    f = GltfFixture{};
    f.lights = R"([{"type": "spot", "spot": {"innerConeAngle": 0.5, "outerConeAngle": 2.0}}])";
    contains(gltf_error(f, "wide_spot"), "KHR_lights_punctual light 0: spot cones");
    std::ofstream(temp_path("broken.gltf")) << "{\"asset\": {\"version\": \"2.0\"}, ";
    try {
        load_gltf<float>(temp_path("broken.gltf"));
        FAIL("no error");
    } catch (const Error& e) {
        contains(e.what(), "broken.gltf");
    }
}

TEST_CASE("scene json: an exported scene reads back exactly and renders bit for bit the same") {
    for (const char* name : {"cornell", "cornell-glossy", "arealight"}) {
        INFO(name);
        const Scene<float> s = builtin_scene<float>(name);
        std::ostringstream text;
        write_scene_json(text, s, SceneJsonView{40, 30, 77});
        const SceneFile<float> f = parse_scene_json<float>(text.str(), "exported.json");
        const Scene<float>& r = f.scene;
        CHECK(f.view.width == 40);
        CHECK(f.view.height == 30);
        CHECK(f.view.max_depth == 77);
        CHECK(r.name == s.name);
        REQUIRE(r.triangles.size() == s.triangles.size());
        CHECK(std::memcmp(r.triangles.data(), s.triangles.data(), s.triangles.size() * sizeof(s.triangles[0])) == 0);
        CHECK(r.material_of == s.material_of);
        CHECK(r.light_of == s.light_of);
        REQUIRE(r.materials.size() == s.materials.size());
        for (std::size_t i = 0; i < s.materials.size(); ++i) {
            CHECK(r.materials[i].kind == s.materials[i].kind);
            CHECK(r.materials[i].kd == s.materials[i].kd);
            CHECK(r.materials[i].emission == s.materials[i].emission);
            CHECK(r.materials[i].exponent == s.materials[i].exponent);
        }
        REQUIRE(r.area_lights.size() == s.area_lights.size());
        for (std::size_t i = 0; i < s.area_lights.size(); ++i) {
            CHECK(r.area_lights[i].vertices == s.area_lights[i].vertices);
            CHECK(r.area_lights[i].area == s.area_lights[i].area);
        }
        CHECK(r.camera.eye == s.camera.eye);
        CHECK(r.camera.fov_y == s.camera.fov_y);
        const RenderResult a = render(s, 3, "halton"), b = render(r, 3, "halton");
        CHECK(std::memcmp(a.image.pixels.data(), b.image.pixels.data(), a.image.size() * sizeof(a.image.pixels[0])) == 0);
        // A file without light_of (written before it was exported) gets it rebuilt.
        std::string old = text.str();
        old.erase(old.find(",\n  \"light_of\""), std::string::npos);
        CHECK(parse_scene_json<float>(old + "\n}\n", "old.json").scene.light_of == s.light_of);
    }
}

TEST_CASE("scene json: bad files are errors naming the file and the line") {
    auto error = [](const std::string& text) -> std::string {
        try {
            parse_scene_json<float>(text, "bad.json");
        } catch (const Error& e) {
            return e.what();
        }
        return "(no error)";
    };
    std::ostringstream text;
    write_scene_json(text, builtin_scene<float>("cornell"), SceneJsonView{});
    const std::string good = text.str();
    CHECK(error(good) == "(no error)");
    std::string s = good;
    s.replace(s.find("\"fov_y\""), 7, "\"fov_x\"");
    CHECK(error(s).find("bad.json:7: member 'fov_y' is missing") != std::string::npos);
    s = good;
    s.replace(s.find("\"lambertian\""), 12, "\"velvet\"");
    CHECK(error(s).find("kind 'velvet' is not one of") != std::string::npos);
    CHECK(error(good + "x").find("text after the end") != std::string::npos);
    CHECK(error("{\"width\": 4,\n \"height\": [1}").find("bad.json:2:") == 0);
    s = good;
    s.replace(s.find("\"material_of\": [") + 16, 1, "99");
    CHECK(error(s).find("material_of = 99") != std::string::npos);
    CHECK(parse_json("[\"a\\u00e9\\ud83d\\ude00\"]", "x").items.at(0).string == "a\xc3\xa9\xf0\x9f\x98\x80");
}

TEST_CASE("scene json: meshes by path, relative to the scene file") {
    std::ofstream(temp_path("mesh.obj")) << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    const std::string head = R"({"width": 8, "height": 6, "max_depth": 4,
        "camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 0.8},
        "materials": [{"kind": "lambertian", "kd": [0.5, 0.5, 0.5], "ks": [0, 0, 0], "exponent": 1, "emission": [0, 0, 0], "ior": 1.5},
                      {"kind": "lambertian", "kd": [0, 0, 0], "ks": [0, 0, 0], "exponent": 1, "emission": [2, 2, 2], "ior": 1.5}],
        "area_lights": [], "point_lights": [],
        "meshes": [{"path": "glint_test_io_mesh.obj", "material": 0}, {"path": )";
    const std::string path = temp_path("meshes.json");
    std::ofstream(path) << head << R"("glint_test_io_mesh.obj", "material": 1}]})";
    const SceneFile<float> f = read_scene_json<float>(path);
    REQUIRE(f.scene.triangles.size() == 4);
    CHECK(f.scene.material_of == std::vector<std::uint32_t>{0, 0, 1, 1});
    CHECK(f.scene.light_of == std::vector<std::int32_t>{-1, -1, 0, 1});
    CHECK(f.scene.area_lights.size() == 2);
    CHECK(f.scene.triangles[2][2] == Vec3f(1, 1, 0));
    std::ofstream(path) << head << R"("no_such_mesh.obj", "material": 1}]})";
    try {
        read_scene_json<float>(path);
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find("no_such_mesh.obj") != std::string::npos);
    }
}

TEST_CASE("EXR: layers and header attributes written and read back, with ZIP, PIZ and no compression") {
    const int w = 37, h = 21;  // not a multiple of ZIP's 16 or PIZ's 32 lines
    Image<Rgb<float>> rgb(w, h);
    ExrLayer albedo{"albedo", {"R", "G", "B"}, {}}, normal{"normal", {"X", "Y", "Z"}, {}}, depth{"depth", {"Z"}, {}};
    Pcg32 rng(17);
    for (int i = 0; i < w * h; ++i) {
        for (std::size_t c = 0; c < 3; ++c) rgb.pixels[std::size_t(i)][c] = rng.uniform<float>() * 100.0f;
        for (std::size_t c = 0; c < 3; ++c) albedo.data.push_back(rng.uniform<float>());
        const Vec3f n = glm::normalize(Vec3f(rng.uniform<float>() - 0.5f, rng.uniform<float>() - 0.5f, 1.0f));
        normal.data.insert(normal.data.end(), {n.x, n.y, n.z});
        depth.data.push_back(i % 7 == 0 ? std::numeric_limits<float>::infinity() : 1.0f + float(i) * 1e-3f);
    }
    const std::vector<ExrAttribute> attributes{{"glint:spp", 64}, {"glint:render_seconds", 1.25},
                                               {"glint:policies", std::string("roulette=throughput direct=mis")}};
    for (const ExrCompression compression : {ExrCompression::zip, ExrCompression::piz, ExrCompression::none}) {
        const std::string path = temp_path("layers_" + std::to_string(int(compression)) + ".exr");
        write_exr(path, rgb, {albedo, normal, depth}, attributes, compression);
        const ExrChannels back = read_exr_channels(path);
        REQUIRE(back.width == w);
        REQUIRE(back.height == h);
        CHECK(back.channels.size() == 10);
        int differ = 0;
        for (std::size_t i = 0; i < std::size_t(w * h); ++i) {
            for (std::size_t c = 0; c < 3; ++c) {
                differ += back.channel(std::string(1, "RGB"[c]))[i] != rgb.pixels[i][c];
                differ += back.channel("albedo." + albedo.channels[c])[i] != albedo.data[3 * i + c];
                differ += back.channel("normal." + normal.channels[c])[i] != normal.data[3 * i + c];
            }
            differ += back.channel("depth.Z")[i] != depth.data[i];  // +inf too
        }
        CHECK(differ == 0);
        REQUIRE(back.attribute("glint:spp"));
        CHECK(std::get<int>(back.attribute("glint:spp")->value) == 64);
        CHECK(std::get<double>(back.attribute("glint:render_seconds")->value) == 1.25);
        CHECK(std::get<std::string>(back.attribute("glint:policies")->value) == "roulette=throughput direct=mis");
        CHECK(back.attribute("glint:nothing") == nullptr);
        CHECK_THROWS_WITH_AS(back.channel("normal.W"), doctest::Contains("no channel 'normal.W' (it has B, G, R, albedo.B"),
                             Error);
        CHECK(read_exr_rgb(path).pixels == rgb.pixels);
    }
}

TEST_CASE("scene json: corner normals are written and read back exactly; meshes keep their vertex normals") {
    Scene<float> s = builtin_scene<float>("cornell");
    s.fill_corner_normals();
    s.corner_normals[3][1] = glm::normalize(Vec3f(0.1f, 0.7f, -0.3f));  // one corner leans
    std::ostringstream text;
    write_scene_json(text, s, SceneJsonView{});
    const Scene<float> r = parse_scene_json<float>(text.str(), "normals.json").scene;
    CHECK(r.corner_normals == s.corner_normals);
    std::string bad = text.str();  // the first triangle's entry left out
    const std::size_t first = bad.find("\n    [", bad.find("\"corner_normals\""));
    bad.erase(first, bad.find("\n    [", first + 1) - first);
    CHECK_THROWS_WITH_AS(parse_scene_json<float>(bad, "bad.json"), doctest::Contains("corner_normals needs one entry"), Error);

    // An OBJ with vertex normals after a mesh without: the first is shaded flat.
    std::ofstream(temp_path("flat.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::ofstream(temp_path("smooth.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0.6 0.8\nvn 0 0 1\nf 1//1 2//2 3//2\n";
    const std::string path = temp_path("normals.json");
    std::ofstream(path) << R"({"width": 8, "height": 6, "max_depth": 4,
        "camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 0.8},
        "materials": [{"kind": "lambertian", "kd": [0.5, 0.5, 0.5], "ks": [0, 0, 0], "exponent": 1, "emission": [0, 0, 0], "ior": 1.5}],
        "area_lights": [], "point_lights": [],
        "meshes": [{"path": "glint_test_io_flat.obj", "material": 0}, {"path": "glint_test_io_smooth.obj", "material": 0}]})";
    const Scene<float> m = read_scene_json<float>(path).scene;
    REQUIRE(m.corner_normals.size() == 2);
    const Vec3f z(0, 0, 1);
    CHECK(m.corner_normals[0] == std::array<Vec3f, 3>{z, z, z});
    CHECK(glm::length(m.corner_normals[1][0] - Vec3f(0, 0.6f, 0.8f)) < 1e-6f);
    CHECK((m.corner_normals[1][1] == z && m.corner_normals[1][2] == z));
}

TEST_CASE("gltf: NORMAL becomes corner normals, turned by the node transforms; bad ones name the accessor") {
    GltfFixture f;
    // Corner normals leaning in the quad's frame; the nodes rotate +z to +y and scale by 2
    // (uniformly: the normals only turn).
    f.normals = {0, 0, 1, 0.6f, 0, 0.8f, 0, 0.6f, 0.8f, -0.6f, 0, 0.8f};
    const Scene<float> s = load_gltf<float>(f.write_gltf("normals"));
    REQUIRE(s.corner_normals.size() == 2);
    // Rotation by -90 degrees about x: (x, y, z) -> (x, z, -y).
    require_close(s.corner_normals[0][0], {0, 1, 0});
    require_close(s.corner_normals[0][1], {0.6f, 0.8f, 0});
    require_close(s.corner_normals[0][2], {0, 0.8f, -0.6f});
    require_close(s.corner_normals[1][2], {-0.6f, 0.8f, 0});
    s.validate();
    f.normals = {0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 1};
    CHECK_THROWS_WITH_AS(load_gltf<float>(f.write_gltf("zero_normal")), doctest::Contains("mesh 0, primitive 0: normal 1 has length 0"), Error);
    f.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    CHECK_THROWS_WITH_AS(load_gltf<float>(f.write_gltf("few_normals")), doctest::Contains("3 normals for 4 positions"), Error);
    CHECK(load_gltf<float>(GltfFixture{}.write_gltf("no_normals")).corner_normals.empty());
}

TEST_CASE("texture: bilinear and nearest lookups, wrap modes, sRGB decoding") {
    const std::array<std::uint8_t, 12> bytes{255, 255, 255, 188, 188, 188, 255, 64, 0, 0, 128, 255};
    Texture<float> t = Texture<float>::from_srgb(2, 2, 3, 8, bytes);
    CHECK(t.texels[0][0] == 1.0f);
    CHECK(t.texels[1][0] == doctest::Approx(0.5029).epsilon(1e-3));  // sRGB 188 / 255 is half the light
    CHECK(t.texels[3][1] == doctest::Approx(0.2158).epsilon(1e-3));
    CHECK(t.texels[2][2] == 0.0f);
    // Texel centres return the texels; midway between two centres, their mean.
    CHECK(t.lookup({0.25f, 0.25f})[1] == doctest::Approx(1.0f));
    CHECK(t.lookup({0.75f, 0.75f})[2] == doctest::Approx(1.0f));
    CHECK(t.lookup({0.5f, 0.25f})[0] == doctest::Approx((1.0f + t.texels[1][0]) / 2));
    // Repeat wraps at the edge: u = 0 lies midway between the last and the first column.
    CHECK(t.lookup({0.0f, 0.25f})[0] == doctest::Approx((1.0f + t.texels[1][0]) / 2));
    CHECK(t.lookup({1.25f, -0.75f})[1] == doctest::Approx(1.0f));
    t.wrap_u = TextureWrap::clamp;
    CHECK(t.lookup({-3.0f, 0.25f})[0] == doctest::Approx(1.0f));
    t.wrap_u = TextureWrap::mirrored_repeat;
    CHECK(t.lookup({-0.25f, 0.25f})[0] == doctest::Approx(1.0f));  // mirrored: -0.25 reads 0.25
    CHECK(t.lookup({1.25f, 0.25f})[0] == doctest::Approx(t.texels[1][0]));  // and 1.25 reads 0.75
    t.nearest = true;
    CHECK(t.lookup({0.49f, 0.51f}) == t.texels[2]);
    CHECK(t.lookup({1e30f, -1e30f}).is_finite());  // far coordinates stay defined
    CHECK_THROWS_AS(Texture<float>::from_srgb(2, 2, 3, 8, std::span<const std::uint8_t>(bytes).first(11)), Error);
}

namespace {

/// The fixture's quad with texture coordinates (0, 0) .. (1, 1) over its corners, a 2 x 2
/// PNG base-colour texture (nearest filtering) of the given texels (rows top first), and a
/// camera 4 units above the floor looking down, which sees each texel in one image quadrant.
GltfFixture textured_fixture(const std::string& name, const std::array<std::uint8_t, 12>& texels) {
    const std::string png = temp_path(name + ".png");
    REQUIRE(stbi_write_png(png.c_str(), 2, 2, 3, texels.data(), 6) != 0);
    GltfFixture f;
    f.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
    f.material = R"({"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.6, 0.4, 1], "baseColorTexture": {"index": 0}, "metallicFactor": 0}})";
    f.extra = R"(, "textures": [{"source": 0, "sampler": 0}], "samplers": [{"magFilter": 9728}], "images": [{"uri": ")" +
              std::filesystem::path(png).filename().string() + "\"}]";
    f.nodes = R"([{"translation": [0, -1, 0], "children": [1]},
        {"mesh": 0, "rotation": [-0.70710678118654752, 0, 0, 0.70710678118654752], "scale": [2, 2, 2]},
        {"camera": 0, "translation": [0, 3, 0], "rotation": [-0.70710678118654752, 0, 0, 0.70710678118654752]},
        {"translation": [0, 1, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}])";
    return f;
}

/// The textured fixture built in C++ without a texture: four quads, each of one texel's kd
/// (the base colour factor times the texel, decoded from sRGB here). Texel (i, j) covers
/// u in [i/2, (i+1)/2), v in [j/2, (j+1)/2): world x in [2i - 2, 2i], z in [-2j, 2 - 2j].
Scene<float> textured_fixture_scene(const std::array<std::uint8_t, 12>& texels) {
    Scene<float> s;
    const auto srgb = [](std::uint8_t c) { return float(c <= 10 ? c / 255.0 / 12.92 : std::pow((c / 255.0 + 0.055) / 1.055, 2.4)); };
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            const std::uint8_t* t = texels.data() + 3 * (2 * j + i);
            const auto m = s.add_material(Material<float>::lambertian(Rgb<float>(0.8f * srgb(t[0]), 0.6f * srgb(t[1]), 0.4f * srgb(t[2]))));
            const float x0 = float(2 * i - 2), x1 = float(2 * i), z0 = float(-2 * j), z1 = float(2 - 2 * j);
            s.add_quad({x0, -1, z1}, {x1, -1, z1}, {x1, -1, z0}, {x0, -1, z0}, m);
        }
    s.point_lights.push_back(PointLight<float>::isotropic({0, 1, 0}, Rgb<float>(5.0f)));
    s.camera = Camera<float>{{0, 3, 0}, {0, 2, 0}, {0, 0, -1}, 0.8f};
    return s;
}

}  // namespace

TEST_CASE("gltf: a base-colour texture renders as the same quad cut into one material per texel") {
    const std::array<std::uint8_t, 12> texels{255, 255, 255, 188, 188, 188, 255, 64, 0, 0, 128, 255};
    const GltfScene<float> g = read_gltf<float>(textured_fixture("textured", texels).write_gltf("textured"));
    CHECK(g.warnings.empty());
    REQUIRE(g.scene.textures.size() == 1);
    CHECK(g.scene.textures[0].nearest);
    CHECK(g.scene.materials.at(0).kd_texture == 0);
    REQUIRE(g.scene.corner_uvs.size() == 2);
    const RenderResult a = render(g.scene, 1), b = render(textured_fixture_scene(texels), 2);
    const double z = quadrant_difference_z(a, b);
    MESSAGE("textured glTF against four quads in C++: " << z << " standard errors apart (largest over quadrants and bands)");
    CHECK(z < 4.0);
    // The comparison can fail: the texture mirrored left to right is told apart.
    const std::array<std::uint8_t, 12> mirrored{188, 188, 188, 255, 255, 255, 0, 128, 255, 255, 64, 0};
    const double swapped = quadrant_difference_z(a, render(textured_fixture_scene(mirrored), 2));
    MESSAGE("against the texture mirrored: " << swapped << " standard errors apart");
    CHECK(swapped > 4.0);
    // The path tracer's integrators that keep materials by index refuse textured scenes.
    CHECK_THROWS_WITH_AS(g.scene.require_untextured("test"), doctest::Contains("textures are applied by the path tracer only"), Error);
}

TEST_CASE("gltf: texture errors name the file and the item") {
    const std::array<std::uint8_t, 12> texels{};
    GltfFixture f = textured_fixture("bad_texture", texels);
    f.extra = R"(, "textures": [{"source": 0}], "images": [{"uri": "no_such_image.png"}])";
    CHECK_THROWS_WITH_AS(load_gltf<float>(f.write_gltf("missing_image")), doctest::Contains("glint_test_io_missing_image.gltf"), Error);
    f = textured_fixture("bad_texture", texels);
    f.uvs.clear();
    CHECK_THROWS_WITH_AS(load_gltf<float>(f.write_gltf("no_uvs")), doctest::Contains("mesh 0, primitive 0: its material has a baseColorTexture but the primitive has no TEXCOORD_0"), Error);
    f = textured_fixture("bad_texture", texels);
    f.uvs[3] = std::numeric_limits<float>::infinity();
    CHECK_THROWS_WITH_AS(load_gltf<float>(f.write_gltf("inf_uv")), doctest::Contains("TEXCOORD_0 accessor 2: coordinate 1 is not finite"), Error);
    f = textured_fixture("bad_texture", texels);
    f.material = R"({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}, "metallicFactor": 0}})";
    const GltfScene<float> other = read_gltf<float>(f.write_gltf("texcoord1"));
    REQUIRE(other.warnings.size() == 1);
    CHECK(other.warnings[0].find("reads TEXCOORD_1") != std::string::npos);
    CHECK(other.scene.materials.at(0).kd_texture == -1);
}

TEST_CASE("scene json: textures, texture coordinates and kd_texture are written and read back exactly") {
    const std::array<std::uint8_t, 12> texels{255, 255, 255, 188, 188, 188, 255, 64, 0, 0, 128, 255};
    Scene<float> s = load_gltf<float>(textured_fixture("json_texture", texels).write_gltf("json_texture"));
    s.textures[0].wrap_v = TextureWrap::mirrored_repeat;
    std::ostringstream text;
    write_scene_json(text, s, SceneJsonView{});
    const Scene<float> r = parse_scene_json<float>(text.str(), "textured.json").scene;
    REQUIRE(r.textures.size() == 1);
    CHECK(r.textures[0].texels == s.textures[0].texels);
    CHECK((r.textures[0].width == 2 && r.textures[0].height == 2 && r.textures[0].nearest));
    CHECK((r.textures[0].wrap_u == TextureWrap::repeat && r.textures[0].wrap_v == TextureWrap::mirrored_repeat));
    CHECK(r.textures[0].source == s.textures[0].source);
    CHECK(r.corner_uvs == s.corner_uvs);
    CHECK(r.materials.at(0).kd_texture == 0);
    const RenderResult a = render(s, 5), b = render(r, 5);
    CHECK(a.image.pixels == b.image.pixels);  // the same scene, the same seed: the same image
    const auto edited = [&](const std::string& from, const std::string& to) {
        std::string t = text.str();
        REQUIRE(t.find(from) != std::string::npos);
        return t.replace(t.find(from), from.size(), to);
    };
    CHECK_THROWS_WITH_AS(parse_scene_json<float>(edited("\"kd_texture\": 0", "\"kd_texture\": 1"), "bad.json"),
                         doctest::Contains("kd_texture = 1.000000 is not an integer in [-1, 0]"), Error);
    const std::string bad = edited("\"texels\": [1", "\"texels\": [2");
    CHECK_THROWS_WITH_AS(parse_scene_json<float>(bad, "bad.json"), doctest::Contains("texture 0: texel 0 is outside [0, 1]"), Error);
}

TEST_CASE("obj: vt and map_Kd texture the floor as the glTF does, within standard errors") {
    const std::array<std::uint8_t, 12> texels{255, 255, 255, 188, 188, 188, 255, 64, 0, 0, 128, 255};
    REQUIRE(stbi_write_png(temp_path("obj_tex.png").c_str(), 2, 2, 3, texels.data(), 6) != 0);
    std::ofstream(temp_path("floor.mtl")) << "newmtl floor\nKd 0.8 0.6 0.4\nmap_Kd glint_test_io_obj_tex.png\n";
    const std::string obj = "mtllib glint_test_io_floor.mtl\nv -2 -1 2\nv 2 -1 2\nv 2 -1 -2\nv -2 -1 -2\n"
                            "vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nusemtl floor\n";  // OBJ's v up from the image's bottom
    std::ofstream(temp_path("floor.obj")) << obj << "f 1/1 2/2 3/3 4/4\n";
    Scene<float> s = obj_scene(load_obj(temp_path("floor.obj")), "floor");
    REQUIRE(s.textures.size() == 1);
    REQUIRE(s.corner_uvs.size() == 2);
    const Scene<float> want = textured_fixture_scene(texels);
    CHECK(!s.textures[0].nearest);  // MTL names no filter: bilinear, glint's default
    s.textures[0].nearest = true;   // as the glTF fixture's sampler asks
    s.environment.reset();  // obj_scene's sky and framing camera, replaced by the fixture's light and view
    s.point_lights = want.point_lights;
    s.camera = want.camera;
    const double z = quadrant_difference_z(render(s, 1), render(want, 2));
    MESSAGE("textured OBJ against four quads in C++: " << z << " standard errors apart");
    CHECK(z < 4.0);
    // Errors name the file and line: a vt index past the vt lines, map_Kd without any vt, a missing image.
    std::ofstream(temp_path("bad_vt.obj")) << obj << "f 1/1 2/2 3/9\n";
    CHECK_THROWS_WITH_AS(load_obj(temp_path("bad_vt.obj")), doctest::Contains("glint_test_io_bad_vt.obj:11: the face names texture coordinate 9 but there are 4 vt lines"), Error);
    std::ofstream(temp_path("no_vt.obj")) << obj << "f 1 2 3\n";
    CHECK_THROWS_WITH_AS(obj_scene(load_obj(temp_path("no_vt.obj")), "no_vt"), doctest::Contains("material 'floor' has map_Kd"), Error);
    std::ofstream(temp_path("floor.mtl")) << "newmtl floor\nKd 0.8 0.6 0.4\nmap_Kd no_such_texture.png\n";
    CHECK_THROWS_WITH_AS(obj_scene(load_obj(temp_path("floor.obj")), "floor"), doctest::Contains("no_such_texture.png"), Error);
}
