// glint-render: the bundled reference path tracer's command line.
//
//   glint-render --scene cornell --size 512 --spp 256 --out cornell.exr
//   glint-render --mesh ../shared/scenes/bunny.obj --spp 64 --out bunny.exr
//
// Renders a built-in scene (cornell, cornell-glossy, furnace, arealight, envmap) or an OBJ
// mesh, writes an OpenEXR file (RGB plus the per-pixel variance layer, and the lambda layer
// of correlated sampling) and a tone-mapped PNG preview next to it, and prints the time and
// the ray throughput. Policies are chosen by flags; see --help.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <unistd.h>

#include <glint/io/exr.hpp>
#include <glint/io/obj.hpp>
#include <glint/io/png.hpp>
#include <glint/io/scene_json.hpp>
#include <glint/tracer/render.hpp>
#include <glint/tracer/scenes.hpp>

using namespace glint;

namespace {

void usage() {
    std::printf(
        "usage: glint-render (--scene NAME | --mesh FILE.obj) [options]\n"
        "  --scene NAME        cornell, cornell-glossy, furnace, arealight, envmap\n"
        "  --mesh FILE         an OBJ (+MTL) mesh; lit by its emissive materials, or by a sky\n"
        "  --env FILE.exr      lat-long environment map (envmap scene or --mesh)\n"
        "  --size N            image width and height (default 256)\n"
        "  --spp N             samples per pixel (default 16)\n"
        "  --out FILE.exr      output (default out.exr; a .png preview is written beside it)\n"
        "  --roulette NAME     classic, spectral, estimate, spectral+estimate (000's rules);\n"
        "                      throughput, throughput+spectral, throughput+estimate,\n"
        "                      throughput+spectral+estimate (the field's rule from --rr-depth);\n"
        "                      none (no roulette, throughput cut-off 1e-3)\n"
        "                      (default throughput+estimate)\n"
        "  --rr-depth N        throughput roulettes: vertices before the first decision (default 3)\n"
        "  --direct NAME       brdf, mis, importance, correlated, combined (default mis)\n"
        "  --selection NAME    BRDF selection: dis, w, mis (default mis)\n"
        "  --light-samples N   light samples per vertex (default 1)\n"
        "  --sampler NAME      random, halton (Owen-scrambled), halton-cp, halton-perm (default random)\n"
        "  --threads N         worker threads (default: all cores)\n"
        "  --weights NAME      roulette band weights H: luminance or mean (default luminance)\n"
        "  --estimate NAME     L~ of the estimate roulettes: pilot (fitted on pilot paths) or scene\n"
        "                      (000's closed-scene formula) (default pilot)\n"
        "  --reduce            estimate roulettes: shorten walks by the estimate's goodness\n"
        "  --pixel-centres     camera rays through pixel centres (default: jittered over the pixel)\n"
        "  --exposure EV       PNG preview exposure (default 0)\n"
        "  --tonemap NAME      PNG preview: clamp (exposure, clip at 1, sRGB) or reinhard\n"
        "                      (x / (1 + x) first) (default clamp)\n"
        "  --seed N            random seed (default 0)\n"
        "  --insert-mesh FILE  put an OBJ mesh (white, Lambertian) on the Cornell box's free floor\n"
        "  --export-scene FILE.json  write the built scene, camera and size as JSON and exit\n");
}

/// A scene from an OBJ: MTL materials (illum 5 mirror, 7 glass, Ns > 0 and Ks > 0 glossy),
/// emissive faces as area lights; a sky if nothing emits; camera framing the bounding box.
Scene<float> scene_from_obj(const std::string& path, const std::string& env_path) {
    const ObjMesh mesh = load_obj(path);
    Scene<float> s;
    s.name = path;
    for (const ObjMaterial& m : mesh.materials) {
        Material<float> mat = Material<float>::lambertian(m.kd, m.ke);
        if (m.illum == 5) mat = Material<float>::mirror(m.ks.max() > 0 ? m.ks : Rgb<float>(0.9f));
        else if (m.illum == 7) mat = Material<float>::dielectric(m.ni > 1.0f ? m.ni : 1.5f);
        else if (m.ks.max() > 0 && m.ns > 0) mat = Material<float>::glossy(m.kd, m.ks, m.ns);
        mat.emission = m.ke;
        s.add_material(mat);
    }
    AABB<float> box;
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        s.add_polygon(mesh.triangles[i], mesh.material[i]);
        for (const auto& p : mesh.triangles[i]) box.extend(p);
    }
    if (!env_path.empty()) {
        s.environment = EnvironmentMap<float>(read_exr_rgb(env_path));
    } else if (s.area_lights.empty()) {
        s.environment = default_sky<float>();
    }
    const Vec3f c = box.center();
    const float r = glm::length(box.extent()) * 0.5f;
    s.camera = Camera<float>{c + Vec3f(0.0f, 0.3f, 1.0f) * (r * 2.6f), c, Vec3f(0, 1, 0), 0.7f};
    return s;
}

int to_int(const char* flag, const char* v) {
    char* end = nullptr;
    const long x = std::strtol(v, &end, 10);
    if (!end || *end || x <= 0 || x > 1 << 20) throw Error(std::string(flag) + " expects a positive integer, got '" + v + "'");
    return int(x);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        std::string scene_name, mesh, env, out = "out.exr", insert, export_json;
        RenderOptions o;
        o.settings.progress = isatty(STDERR_FILENO) != 0;  // a progress bar only on a terminal
        float exposure = 0;
        bool reinhard = false;
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            auto value = [&]() -> const char* {
                if (i + 1 >= argc) throw Error(a + " expects a value");
                return argv[++i];
            };
            if (a == "--help" || a == "-h") { usage(); return 0; }
            else if (a == "--scene") scene_name = value();
            else if (a == "--mesh") mesh = value();
            else if (a == "--env") env = value();
            else if (a == "--size") o.settings.width = o.settings.height = to_int("--size", value());
            else if (a == "--spp") o.settings.spp = to_int("--spp", value());
            else if (a == "--out") out = value();
            else if (a == "--roulette") o.roulette = value();
            else if (a == "--rr-depth") o.rr_depth = to_int("--rr-depth", value());
            else if (a == "--direct") o.direct = value();
            else if (a == "--selection") o.settings.selection = parse_selection(value());
            else if (a == "--light-samples") o.settings.light_samples = to_int("--light-samples", value());
            else if (a == "--sampler") o.sampler = value();
            else if (a == "--threads") o.settings.threads = to_int("--threads", value());
            else if (a == "--weights") o.roulette_weights = value();
            else if (a == "--estimate") o.radiance_estimate = value();
            else if (a == "--reduce") o.reduce_continuation = true;
            else if (a == "--pixel-centres") o.settings.pixel_jitter = false;
            else if (a == "--exposure") exposure = std::strtof(value(), nullptr);
            else if (a == "--tonemap") {
                const std::string t = value();
                if (t != "clamp" && t != "reinhard") throw Error("--tonemap expects clamp or reinhard, not '" + t + "'");
                reinhard = t == "reinhard";
            }
            else if (a == "--seed") o.seed = std::strtoull(value(), nullptr, 10);
            else if (a == "--insert-mesh") insert = value();
            else if (a == "--export-scene") export_json = value();
            else throw Error("unknown option '" + a + "' (see --help)");
        }
        if (scene_name.empty() == mesh.empty()) throw Error("give exactly one of --scene NAME and --mesh FILE (see --help)");
        Scene<float> scene = mesh.empty() ? builtin_scene<float>(scene_name) : scene_from_obj(mesh, env);
        if (!env.empty() && mesh.empty()) scene.environment = EnvironmentMap<float>(read_exr_rgb(env));
        if (!insert.empty())
            insert_mesh<float>(scene, load_obj(insert).triangles, Material<float>::lambertian(Rgb<float>(0.725f, 0.71f, 0.68f)),
                               cornell_mesh_placement<float>());
        if (!export_json.empty()) {
            write_scene_json(export_json, scene, SceneJsonView{o.settings.width, o.settings.height, o.settings.max_depth});
            return 0;
        }

        std::fprintf(stderr, "%s: %zu triangles, %zu area lights%s; %dx%d, %d spp, roulette %s, direct %s\n",
                     scene.name.c_str(), scene.triangles.size(), scene.area_lights.size(),
                     scene.environment ? ", environment map" : "", o.settings.width, o.settings.height,
                     o.settings.spp, o.roulette.c_str(), o.direct.c_str());
        const RenderAccel accel(scene.triangles);
        const RenderResult r = render(scene, accel, o);

        std::vector<ExrLayer> layers;
        ExrLayer var{"variance", {"R", "G", "B"}, {}};
        for (const auto& p : r.variance.pixels) var.data.insert(var.data.end(), {p[0], p[1], p[2]});
        layers.push_back(std::move(var));
        if (o.direct == "importance" || o.direct == "correlated" || o.direct == "combined")
            layers.push_back(ExrLayer{"lambda", {"Y"}, r.lambda.pixels});
        write_exr(out, r.image, layers);
        const std::string png = (out.size() > 4 && out.substr(out.size() - 4) == ".exr" ? out.substr(0, out.size() - 4) : out) + ".png";
        write_png(png, r.image, exposure, reinhard);
        std::printf("rendered %s in %.2f s (build %.2f s): %.2f Mrays/s, %llu rays, %.2f rays/path; wrote %s and %s\n",
                    scene.name.c_str(), r.seconds, accel.build_seconds(), double(r.rays) / r.seconds * 1e-6,
                    (unsigned long long)r.rays, double(r.rays) / double(std::max<std::uint64_t>(r.paths, 1)), out.c_str(),
                    png.c_str());
        if (r.capped_walks > 0)
            std::fprintf(stderr, "glint-render: warning: %llu walks reached the depth cap of %d vertices and were cut "
                         "(biased); raise RenderSettings::max_depth\n", (unsigned long long)r.capped_walks, o.settings.max_depth);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "glint-render: %s\n", e.what());
        return 1;
    }
}
