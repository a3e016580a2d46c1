// glint-render: the bundled reference path tracer's command line.
//
//   glint-render --scene cornell --size 512 --spp 256 --out cornell.exr
//   glint-render --mesh ../shared/scenes/bunny.obj --spp 64 --out bunny.exr
//   glint-render --scene-file room.glb --spp 64 --out room.exr
//
// Renders a built-in scene (cornell, cornell-glossy, furnace, arealight, envmap), an OBJ
// mesh or a scene file (glTF 2.0, or the JSON that --export-scene writes), prints the camera
// it used as flags (so that a framed mesh's view can be given again), writes an OpenEXR file (RGB plus the per-pixel variance layer and the integrator's
// layers, such as correlated sampling's lambda) and a tone-mapped PNG preview next to it, and
// prints the time and the ray throughput. Policies are chosen by name (the tables of
// glint/tracer/named_render.hpp and accelerator_choices.hpp), every name checked before any
// file is read; see --help.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <unistd.h>

#include <glint/io/exr.hpp>
#include <glint/io/gltf.hpp>
#include <glint/version.hpp>
#include <glint/io/obj.hpp>
#include <glint/io/obj_scene.hpp>
#define GLINT_STB_IMPLEMENTATION  // stb_image_write's functions, compiled in this file
#include <glint/io/png.hpp>
#include <glint/io/scene_json.hpp>
#include <glint/io/scene_json_read.hpp>
#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/first_hit_layers.hpp>
#include <glint/tracer/named_render.hpp>
#include "glint_instances.hpp"  // render_named for AnyAccel, compiled once (instances/)
#include <glint/tracer/progressive.hpp>
#include <glint/tracer/scenes.hpp>
#include <glint/tracer/smooth_normals.hpp>

#include "flags.hpp"  // cli/: the command-line conventions
#include "photon_cli.hpp"
#include "vpl_cli.hpp"

using namespace glint;

namespace {

enum class Tonemap { clamp, reinhard };
constexpr Choice<Tonemap> tonemaps[] = {{"clamp", "exposure, clip at 1, sRGB", Tonemap::clamp},
                                        {"reinhard", "x / (1 + x) first", Tonemap::reinhard}};
enum class IntegratorKind { path, vpl, sppm, photons };
constexpr Choice<IntegratorKind> integrators[] = {
    {"path", "the path tracer (with --time-budget: passes of --spp samples per pixel)", IntegratorKind::path},
    {"vpl", "virtual light sources (one ray per pixel centre; --spp, --roulette, --direct and --sampler do not apply; "
            "no passes)", IntegratorKind::vpl},
    {"sppm", "stochastic progressive photon mapping (Hachisuka and Jensen 2009): --spp passes, or passes for "
             "--time-budget", IntegratorKind::sppm},
    {"photons", "photon mapping (Jensen 2001): direct light, caustic map, final gather from the global map; with "
                "--time-budget, passes of new maps", IntegratorKind::photons}};
constexpr Choice<bool> visibilities[] = {{"rays", "shadow rays", false},
                                         {"spheres", "occluder spheres from --insert-mesh or --mesh", true}};
constexpr Choice<VplGather> gathers[] = {{"all", "every VPL, a shadow ray each", VplGather::all},
                                         {"cuts", "through a light cut of the VPLs (Fernandez 2004 5.2; biased)", VplGather::cuts}};

/// load_obj, its warnings printed.
ObjMesh load_obj_warning(const std::string& path) {
    ObjMesh mesh = load_obj(path);
    for (const std::string& w : mesh.warnings) std::fprintf(stderr, "glint-render: warning: %s\n", w.c_str());
    return mesh;
}

/// A scene from an OBJ (io/obj_scene.hpp: MTL materials mapped, emissive faces as lights, a
/// sky if nothing emits, a camera framing it); --env replaces the sky.
Scene<float> scene_from_obj(const std::string& path, const std::string& env_path) {
    Scene<float> s = obj_scene(load_obj_warning(path), path);
    if (!env_path.empty()) s.environment = EnvironmentMap<float>(read_exr_rgb(env_path));
    return s;
}

/// "X,Y,Z" as three finite numbers, or nothing.
std::optional<Vec3f> parse_vec3(const std::string& text) {
    float c[3];
    const char* p = text.c_str();
    for (int k = 0; k < 3; ++k) {
        char* end = nullptr;
        c[k] = std::strtof(p, &end);
        if (end == p || *end != (k < 2 ? ',' : '\0') || !std::isfinite(c[k])) return std::nullopt;
        p = end + 1;
    }
    return Vec3f(c[0], c[1], c[2]);
}

/// A flag whose value is a point or direction X,Y,Z.
cli::Flag* vec3_flag(cli::App& app, const std::string& flag, std::optional<Vec3f>& target, const std::string& help) {
    const auto set = [&target](const std::string& t) {
        target = parse_vec3(t);
        return target ? std::string() : "expects three finite numbers X,Y,Z, got '" + t + "'";
    };
    return app.value(flag, set, help, "X,Y,Z", "");
}

bool ends_with(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// Everything the command line sets besides the path tracer's NamedRender.
struct Args {
    std::string scene_name, mesh, scene_file, env, out = "out.exr";
    bool width_given = false, height_given = false, depth_given = false;  // over a scene file's
    std::string insert, export_json;  // --insert-mesh, --export-scene
    std::string accel = "bvh8", tonemap = "clamp";
    float exposure = 0;
    std::optional<Vec3f> eye, look_at, up;
    std::optional<float> fov_degrees;
    std::string integrator = "path";
    double time_budget = 0;  // --time-budget: seconds of passes, 0: one render
    bool aov = false;        // --aov: the first-hit layers (path integrator)
    std::optional<float> smooth;  // --smooth DEGREES: corner normals for a mesh or scene file
    VplCliOptions vpl;
    PhotonCliOptions photons;
};

/// Throws for a flag given to a scene it does not act on: --insert-mesh stands a mesh on the
/// Cornell box's free floor; --env lights open scenes (envmap, a mesh, a scene file), while
/// the other built-in scenes are closed or lit by their own lights.
void check_scene_flags(const Args& g) {
    if (!g.insert.empty() && g.scene_name != "cornell" && g.scene_name != "cornell-glossy")
        throw Error("--insert-mesh applies to --scene cornell and cornell-glossy (it stands the mesh on their free floor), "
                    "not to " + (g.scene_name.empty() ? std::string("--mesh or --scene-file") : "'" + g.scene_name + "'"));
    if (g.smooth && !g.scene_name.empty())
        throw Error("--smooth applies to --mesh and --scene-file, not to the built-in scene '" + g.scene_name + "'");
    if (!g.env.empty() && !g.scene_name.empty() && g.scene_name != "envmap")
        throw Error("--env applies to --scene envmap, --mesh and --scene-file, not to the built-in scene '" + g.scene_name +
                    "' (lit by its own lights)");
}

/// The flags that choose the scene, the camera and the output.
void add_scene_flags(cli::App& app, Args& g) {
    cli::choice(app, "--scene", g.scene_name, scene_choices<float>(), "scene", "a built-in scene")->group("Scene");
    cli::text(app, "--mesh", g.mesh, "an OBJ (+MTL) mesh; lit by its emissive materials, or by a sky")->group("Scene");
    cli::text(app, "--scene-file", g.scene_file,
              "FILE.gltf or FILE.glb: a glTF 2.0 scene (meshes, materials, the first camera, KHR_lights_punctual "
              "lights; a sky if nothing emits); FILE.json: a scene --export-scene wrote (its size and --max-depth "
              "unless given)")->group("Scene");
    cli::text(app, "--env", g.env, "FILE.exr: a lat-long environment map (envmap scene, --mesh or --scene-file)")->group("Scene");
    cli::number_to<float>(app, "--smooth", [&g](float d) { g.smooth = d; }, 0.0f, 180.0f,
                          "--mesh or --scene-file: shade smoothly with corner normals averaged over the faces within "
                          "DEGREES of each other, replacing the file's normals")->group("Scene");
    cli::text(app, "--insert-mesh", g.insert,
              "an OBJ mesh (white, Lambertian) on the Cornell box's free floor (cornell, cornell-glossy)")->group("Scene");
    cli::text(app, "--export-scene", g.export_json, "FILE.json: write the built scene, camera and size, and exit")->group("Scene");
    vec3_flag(app, "--eye", g.eye, "camera position (default: the scene's; a mesh is framed by its box)")->group("Camera");
    vec3_flag(app, "--look-at", g.look_at, "the point the camera looks at")->group("Camera");
    vec3_flag(app, "--up", g.up, "the camera's up direction")->group("Camera");
    cli::number_to<float>(app, "--fov", [&g](float d) { g.fov_degrees = d; }, 0.01f, 179.0f,
                          "vertical field of view, degrees")->group("Camera");
    cli::text(app, "--out", g.out,
              "FILE.exr or FILE.png: writes FILE.exr (RGB, variance and the integrator's layers) and the tone-mapped "
              "preview FILE.png")->group("Output");
    cli::flag(app, "--aov", g.aov, "path: also the first-hit layers albedo, normal and depth in FILE.exr")->group("Output");
    cli::number(app, "--exposure", g.exposure, -64.0f, 64.0f, "PNG preview exposure, EV")->group("Output");
    cli::choice(app, "--tonemap", g.tonemap, std::span<const Choice<Tonemap>>(tonemaps), "tonemap", "PNG preview")
        ->group("Output");
}

/// The image's flags (size, samples, threads) and the path tracer's policies by name.
void add_render_flags(cli::App& app, Args& g, NamedRender<float>& o) {
    cli::number_to<int>(app, "--size", [&](int n) { o.image.width = o.image.height = n, g.width_given = g.height_given = true; },
                        1, 16384, "image width and height (default 256)")->group("Image");
    cli::number_to<int>(app, "--width", [&](int n) { o.image.width = n, g.width_given = true; }, 1, 16384,
                        "image width (over --size)")->group("Image");
    cli::number_to<int>(app, "--height", [&](int n) { o.image.height = n, g.height_given = true; }, 1, 16384,
                        "image height (over --size)")->group("Image");
    cli::number(app, "--spp", o.image.spp, 1, 1 << 20, "samples per pixel")->group("Image");
    cli::number_to<int>(app, "--threads", [&o](int n) { o.image.threads = n; }, 1, 4096, "worker threads (default: all cores)")
        ->group("Image");
    app.flag("--pixel-centres", [&o] { o.image.pixel_jitter = false; },
                          "camera rays through pixel centres (default: jittered over the pixel)")
        ->group("Image");
    cli::number(app, "--seed", o.seed, std::uint64_t(0), ~std::uint64_t(0), "random seed")->group("Image");
    cli::number(app, "--time-budget", g.time_budget, 1e-3, 1e6,
                "progressive passes until the seconds are spent (path, sppm, photons); prints the passes done")->group("Image");
    cli::choice(app, "--integrator", g.integrator, std::span<const Choice<IntegratorKind>>(integrators), "integrator",
                "the integrator")->group("Image");
    cli::choice(app, "--accel", g.accel, accelerator_choices(), "accelerator", "ray accelerator")->group("Image");
    cli::number_to<int>(app, "--max-depth", [&](int n) { o.tracer.max_depth = n, g.depth_given = true; }, 1, 1 << 24,
                        "path length cap (default 1024)")->group("Path tracer");
    cli::text(app, "--roulette", o.roulette,
              "the roulette rule; each also as NAME+estimate (Szecsi 2009 2.3's radiance estimate on top; estimate = "
              "classic+estimate):\n" + choice_usage(roulette_choices<float>(), 4), "NAME")->group("Path tracer");
    cli::number(app, "--rr-depth", o.rr_depth, 0, 1 << 20, "throughput roulettes: vertices before the first decision")
        ->group("Path tracer");
    cli::choice(app, "--direct", o.direct, direct_choices<float>(), "direct lighting", "direct lighting")->group("Path tracer");
    cli::choice(app, "--selection", o.selection, selection_choices(), "BRDF selection", "BRDF selection")->group("Path tracer");
    cli::number(app, "--light-samples", o.tracer.light_samples, 1, 1024, "light samples per vertex")->group("Path tracer");
    cli::choice(app, "--sampler", o.sampler, sampler_choices<float>(), "sampler", "sampler")->group("Path tracer");
    cli::choice(app, "--weights", o.weights, weights_choices<float>(), "roulette weights", "roulette band weights H")
        ->group("Path tracer");
    cli::choice(app, "--estimate", o.estimate, estimate_choices(), "radiance estimate", "L~ of the +estimate roulettes")
        ->group("Path tracer");
    cli::flag(app, "--reduce", o.reduce_continuation, "+estimate roulettes: shorten walks by the estimate's goodness")
        ->group("Path tracer");
}

/// The VPL and photon integrators' flags.
void add_integrator_flags(cli::App& app, Args& g) {
    VplCliOptions& v = g.vpl;
    PhotonCliOptions& p = g.photons;
    cli::number(app, "--vpls", v.vpls, std::size_t(1), std::size_t(1) << 24, "shooting walks")->group("VPL");
    cli::choice(app, "--visibility", v.visibility, std::span<const Choice<bool>>(visibilities), "visibility", "visibility")
        ->group("VPL");
    cli::number(app, "--spheres", v.spheres, std::size_t(1), std::size_t(1) << 20, "occluder spheres")->group("VPL");
    cli::number(app, "--clamp", v.clamp, 0.0, 1e30, "clamp the geometry term at this distance (0: unbiased)")->group("VPL");
    cli::choice(app, "--gather", v.gather, std::span<const Choice<VplGather>>(gathers), "gather", "the VPL sum")->group("VPL");
    cli::number(app, "--photons", p.photons, std::size_t(1), std::size_t(1) << 32, "sppm, photons: photons emitted per pass")
        ->group("Photons");
    cli::number(app, "--radius", p.radius, 1e-6, 1e6, "sppm: initial gather radius; photons: largest kNN radius")
        ->group("Photons");
    cli::number(app, "--camera-samples", p.camera_samples, 1, 1 << 16,
                "sppm: camera rays per pixel and pass for emission and direct light")->group("Photons");
    cli::number(app, "--knn", p.knn, 1, 1 << 16, "photons: photons per radiance estimate")->group("Photons");
    cli::number(app, "--final-gather", p.gather_rays, 0, 1 << 16, "photons: final gather rays per pixel sample")
        ->group("Photons");
}

/// Parses and validates every flag (nothing long runs before this returns). Returns false
/// after --help or --version.
bool parse_args(int argc, char** argv, Args& g, NamedRender<float>& o) {
    cli::App app("glint-render: renders a built-in scene (--scene), an OBJ mesh (--mesh) or a scene file "
                 "(--scene-file) into an EXR and a PNG preview");
    app.version(std::string("glint-render ") + version_string);
    add_scene_flags(app, g);
    add_render_flags(app, g, o);
    add_integrator_flags(app, g);
    if (!cli::parse(app, argc, argv)) return false;
    glint::check_names(o);  // the roulette's NAME+estimate grammar
    if (g.time_budget > 0 && g.integrator == "vpl")
        throw Error("--time-budget applies to integrators with passes (path, sppm, photons), not '" + g.integrator + "'");
    if (g.aov && g.integrator != "path") throw Error("--aov applies to the path integrator, not '" + g.integrator + "'");
    if (int(!g.scene_name.empty()) + int(!g.mesh.empty()) + int(!g.scene_file.empty()) != 1)
        throw Error("give exactly one of --scene NAME, --mesh FILE and --scene-file FILE (see --help)");
    if (!g.scene_file.empty() && !ends_with(g.scene_file, ".gltf") && !ends_with(g.scene_file, ".glb") &&
        !ends_with(g.scene_file, ".json"))
        throw Error("--scene-file: expects FILE.gltf, FILE.glb or FILE.json, got '" + g.scene_file + "'");
    if (std::uint64_t(o.image.width) * std::uint64_t(o.image.height) > (std::uint64_t(1) << 26))
        throw Error("--width x --height = " + std::to_string(o.image.width) + " x " + std::to_string(o.image.height) +
                    " is above the limit of 2^26 pixels");
    if (!ends_with(g.out, ".exr") && !ends_with(g.out, ".png"))
        throw Error("--out: expects a file name ending in .exr or .png, got '" + g.out + "'");
    for (const char* ext : {".exr", ".png"}) cli::check_writable(g.out.substr(0, g.out.size() - 4) + ext);
    if (!g.export_json.empty() && !ends_with(g.export_json, ".json"))
        throw Error("--export-scene: expects a file name ending in .json, got '" + g.export_json + "'");
    if (!g.export_json.empty()) cli::check_writable(g.export_json);
    check_scene_flags(g);
    for (const std::string& f : {g.mesh, g.scene_file, g.env})
        if (!f.empty() && access(f.c_str(), R_OK) != 0) throw Error("cannot read '" + f + "': " + std::strerror(errno));
    return true;
}

/// --scene-file FILE.json: the exported scene, its image size and depth cap where no flag set them.
Scene<float> scene_from_json(const Args& g, NamedRender<float>& o) {
    SceneFile<float> f = read_scene_json<float>(g.scene_file);
    if (!g.width_given) o.image.width = std::min(f.view.width, 16384);
    if (!g.height_given) o.image.height = std::min(f.view.height, 16384);
    if (!g.depth_given) o.tracer.max_depth = f.view.max_depth;
    if (!g.env.empty()) f.scene.environment = EnvironmentMap<float>(read_exr_rgb(g.env));
    if (std::uint64_t(o.image.width) * std::uint64_t(o.image.height) > (std::uint64_t(1) << 26))
        throw Error(g.scene_file + ": image " + std::to_string(o.image.width) + " x " + std::to_string(o.image.height) +
                    " is above the limit of 2^26 pixels (give --width and --height)");
    return std::move(f.scene);
}

/// --scene-file FILE.gltf / FILE.glb: the glTF scene; its camera's aspect sets the height
/// where no flag set the size; a framing camera if it has none; a sky if nothing emits.
Scene<float> scene_from_gltf(const Args& g, NamedRender<float>& o) {
    GltfScene<float> f = read_gltf<float>(g.scene_file);
    for (const std::string& w : f.warnings) std::fprintf(stderr, "glint-render: warning: %s\n", w.c_str());
    if (f.aspect > 0.0f && !g.width_given && !g.height_given)
        o.image.height = std::clamp(int(std::lround(float(o.image.width) / f.aspect)), 1, 16384);
    sky_and_framing(f.scene, f.has_camera);
    if (!g.env.empty()) f.scene.environment = EnvironmentMap<float>(read_exr_rgb(g.env));
    return std::move(f.scene);
}

/// The scene the flags name (the image size and depth cap from a scene file where no flag set them).
Scene<float> load_scene(const Args& g, NamedRender<float>& o) {
    if (g.scene_file.empty() && g.mesh.empty()) {
        Scene<float> s = builtin_scene<float>(g.scene_name);
        if (!g.env.empty()) s.environment = EnvironmentMap<float>(read_exr_rgb(g.env));
        return s;
    }
    Scene<float> s = !g.mesh.empty() ? scene_from_obj(g.mesh, g.env)
                     : ends_with(g.scene_file, ".json") ? scene_from_json(g, o) : scene_from_gltf(g, o);
    if (g.smooth) smooth_corner_normals(s, *g.smooth);
    return s;
}

/// The camera as the flags that give it again.
void print_camera(const Camera<float>& c) {
    std::fprintf(stderr, "camera: --eye %.9g,%.9g,%.9g --look-at %.9g,%.9g,%.9g --up %.9g,%.9g,%.9g --fov %.9g\n", c.eye.x,
                 c.eye.y, c.eye.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y, c.up.z,
                 double(c.fov_y) * 180.0 / 3.14159265358979323846);
}

/// An RGB image's floats, pixel after pixel (an EXR layer's data).
std::vector<float> flatten(const Image<Rgb<float>>& img) {
    std::vector<float> out;
    for (const auto& p : img.pixels) out.insert(out.end(), {p[0], p[1], p[2]});
    return out;
}

/// The camera flags over the scene's camera; throws for a degenerate frame.
void apply_camera(const Args& g, Camera<float>& c) {
    if (g.eye) c.eye = *g.eye;
    if (g.look_at) c.target = *g.look_at;
    if (g.up) c.up = *g.up;
    if (g.fov_degrees) c.fov_y = *g.fov_degrees * 3.14159265f / 180.0f;
    const Vec3f w = c.target - c.eye;
    if (!(glm::length(w) > 0.0f)) throw Error("--eye and --look-at must differ");
    if (!(glm::length(glm::cross(w, c.up)) > 0.0f)) throw Error("--up must not be parallel to the view direction");
}


/// The film's layers for the EXR file: the variance, then each layer the integrator added
/// (a grey layer as one channel Y).
std::vector<ExrLayer> exr_layers(const Film& film) {
    std::vector<ExrLayer> out{ExrLayer{"variance", {"R", "G", "B"}, flatten(film.variance)}};
    for (const FilmLayer& l : film.layers) {
        if (!l.grey) {
            out.push_back(ExrLayer{l.name, {"R", "G", "B"}, flatten(l.pixels)});
            continue;
        }
        ExrLayer y{l.name, {"Y"}, {}};
        for (const auto& p : l.pixels.pixels) y.data.push_back(p[0]);
        out.push_back(std::move(y));
    }
    return out;
}

/// The EXR header's record of a render: glint's version, the samples per pixel, the seconds
/// and the policies by name.
std::vector<ExrAttribute> exr_attributes(const Args& g, const NamedRender<float>& o, int spp, double seconds) {
    std::string policies = "integrator=" + g.integrator + " accel=" + g.accel;
    if (g.integrator == "path")
        policies += " roulette=" + o.roulette + " direct=" + o.direct + " selection=" + o.selection + " sampler=" +
                    o.sampler + " weights=" + o.weights + " estimate=" + o.estimate;
    return {{"glint:version", std::string(version_string)}, {"glint:spp", spp}, {"glint:render_seconds", seconds},
            {"glint:policies", policies}};
}

/// --aov: the first-hit layers of the beauty pass's camera rays (all `spp` of each pixel's
/// samples, from sample 0), as EXR layers albedo.RGB, normal.XYZ and depth.Z.
std::vector<ExrLayer> first_hit_exr_layers(const Scene<float>& scene, const AnyAccel& accel,
                                           NamedRender<float> o, int spp) {
    o.image.spp = spp;
    o.image.first_sample = 0;
    const auto start = std::chrono::steady_clock::now();
    const FirstHitImages f = render_first_hit_named(scene, accel, o);
    std::fprintf(stderr, "first-hit layers in %.3f s\n",
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return {ExrLayer{"albedo", {"R", "G", "B"}, flatten(f.albedo)}, ExrLayer{"normal", {"X", "Y", "Z"}, flatten(f.normal)},
            ExrLayer{"depth", {"Z"}, f.depth.pixels}};
}

/// The tree --accel names over the scene's triangles, and the seconds its build took.
std::pair<AcceleratorChoice, double> build_accel(const Args& g, const Scene<float>& scene) {
    const auto start = std::chrono::steady_clock::now();
    AcceleratorChoice accel = find_choice(accelerator_choices(), "accelerator", g.accel).make(scene.triangles);
    return {std::move(accel), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
}

/// The path tracer's render through `accel` (built in build_seconds); prints what it did.
int render_path(const Args& g, const NamedRender<float>& o, const Scene<float>& scene, const AnyAccel& accel,
                double build_seconds) {
    std::fprintf(stderr, "%s: %zu triangles, %zu area lights%s; %dx%d, %d spp, roulette %s, direct %s\n", scene.name.c_str(),
                 scene.triangles.size(), scene.area_lights.size(), scene.environment ? ", environment map" : "",
                 o.image.width, o.image.height, o.image.spp, o.roulette.c_str(), o.direct.c_str());
    ProgressiveResult r;
    if (g.time_budget > 0) {
        // Passes of --spp samples continuing one sequence (pass k: samples k spp ..), averaged.
        r = render_passes(PassBudget{g.time_budget, 0}, [&](int k) {
            NamedRender<float> pass = o;
            pass.image.first_sample = std::uint64_t(k) * std::uint64_t(o.image.spp);
            return render_named(scene, accel, pass);
        });
    } else {
        static_cast<RenderResult&>(r) = render_named(scene, accel, o);
        r.passes = 1;
    }
    const std::string stem = g.out.substr(0, g.out.size() - 4), exr = stem + ".exr", png = stem + ".png";
    std::vector<ExrLayer> layers = exr_layers(r);
    if (g.aov)
        for (ExrLayer& l : first_hit_exr_layers(scene, accel, o, r.passes * o.image.spp)) layers.push_back(std::move(l));
    write_exr(exr, r.image, layers, exr_attributes(g, o, r.passes * o.image.spp, r.seconds));
    write_png(png, r.image, g.exposure, g.tonemap == "reinhard");
    std::printf("rendered %s in %.3f s (build %s %.3f s): %.2f Mrays/s, %llu rays, %.2f rays/path; wrote %s and %s\n",
                scene.name.c_str(), r.seconds, g.accel.c_str(), build_seconds, double(r.rays) / r.seconds * 1e-6,
                (unsigned long long)r.rays, double(r.rays) / double(std::max<std::uint64_t>(r.paths, 1)), exr.c_str(),
                png.c_str());
    if (g.time_budget > 0)
        std::printf("passes: %d of %d spp (%d spp) in %.3f s, budget %.3f s\n", r.passes, o.image.spp, r.passes * o.image.spp,
                    r.seconds, g.time_budget);
    if (r.capped_walks > 0)
        std::fprintf(stderr, "glint-render: warning: %llu walks reached the depth cap of %d vertices and were cut "
                     "(biased); raise --max-depth\n", (unsigned long long)r.capped_walks, o.tracer.max_depth);
    return 0;
}

/// The render's EXR (no variance layer: progressive photon mapping keeps none) and PNG.
void write_images(const Args& g, const Image<Rgb<float>>& image, const std::vector<ExrAttribute>& attributes) {
    const std::string stem = g.out.substr(0, g.out.size() - 4);
    write_exr(stem + ".exr", image, {}, attributes);
    write_png(stem + ".png", image, g.exposure, g.tonemap == "reinhard");
}

/// --integrator sppm: --spp passes, or passes for --time-budget seconds.
int render_sppm_main(const Args& g, const NamedRender<float>& o, const Scene<float>& scene, const AnyAccel& accel,
                     double build_seconds) {
    const PassBudget budget = g.time_budget > 0 ? PassBudget{g.time_budget, 0} : PassBudget{0, o.image.spp};
    const SppmResult r = render_sppm_cli(scene, accel, g.photons, o.image, budget, o.seed);
    write_images(g, r.image, exr_attributes(g, o, r.passes * g.photons.camera_samples, r.seconds));
    std::printf("rendered %s with SPPM in %.3f s (build %s %.3f s): %d passes of %zu photons (%zu emitted), mean radius "
                "%.4g (from %.4g), photon passes %.3f s; wrote %s\n",
                scene.name.c_str(), r.seconds, g.accel.c_str(), build_seconds, r.passes, g.photons.photons,
                r.photons_emitted, r.mean_radius, g.photons.radius, r.photon_seconds, g.out.c_str());
    std::printf("passes: %d in %.3f s%s\n", r.passes, r.seconds,
                g.time_budget > 0 ? (", budget " + std::to_string(g.time_budget) + " s").c_str() : "");
    return 0;
}

/// --integrator photons: one render of --spp samples, or passes of new maps for --time-budget.
int render_photons_main(const Args& g, const NamedRender<float>& o, const Scene<float>& scene, const AnyAccel& accel,
                        double build_seconds) {
    const PassBudget budget = g.time_budget > 0 ? PassBudget{g.time_budget, 0} : PassBudget{0, 1};
    const ProgressiveResult r = render_photons_cli(scene, accel, g.photons, o.image, budget, o.seed);
    write_images(g, r.image, exr_attributes(g, o, r.passes * o.image.spp, r.seconds));
    std::printf("rendered %s with photon maps in %.3f s (build %s %.3f s): %zu + %zu photons per pass, k %d, radius "
                "%.4g, %d gather rays, %d spp per pass; wrote %s\n",
                scene.name.c_str(), r.seconds, g.accel.c_str(), build_seconds, g.photons.photons, 4 * g.photons.photons,
                g.photons.knn, g.photons.radius, g.photons.gather_rays, o.image.spp, g.out.c_str());
    std::printf("passes: %d in %.3f s%s\n", r.passes, r.seconds,
                g.time_budget > 0 ? (", budget " + std::to_string(g.time_budget) + " s").c_str() : "");
    return 0;
}

/// glint-render's progress bar on stderr: the share of tiles finished, the seconds spent and
/// the seconds left at the mean rate so far.
void progress_bar(const RenderProgress& p) {
    const int tiles = std::max(p.tiles, 1), bar = 40 * p.tiles_done / tiles;
    const double left = p.tiles_done > 0 ? p.seconds * double(tiles - p.tiles_done) / double(p.tiles_done) : 0.0;
    std::fprintf(stderr, "\r[%.*s%.*s] %3d%%  %.1f s, %.1f s left   ", bar, "########################################", 40 - bar,
                 "                                        ", 100 * p.tiles_done / tiles, p.seconds, left);
    if (p.tiles_done == tiles) std::fprintf(stderr, "\n");
}

}  // namespace

int main(int argc, char** argv) {
    try {
        Args g;
        NamedRender<float> o;
        if (isatty(STDERR_FILENO) != 0) o.image.progress = progress_bar;  // a progress bar only on a terminal
        if (!parse_args(argc, argv, g, o)) return 0;
        Scene<float> scene = load_scene(g, o);
        apply_camera(g, scene.camera);
        print_camera(scene.camera);
        const std::size_t before_insert = g.mesh.empty() ? scene.triangles.size() : 0;  // occluders: the mesh
        if (!g.insert.empty())
            insert_mesh<float>(scene, load_obj_warning(g.insert).triangles, Material<float>::lambertian(Rgb<float>(0.725f, 0.71f, 0.68f)),
                               cornell_mesh_placement<float>());
        if (!g.export_json.empty()) {
            write_scene_json(g.export_json, scene, SceneJsonView{o.image.width, o.image.height, o.tracer.max_depth});
            return 0;
        }
        const auto [accel, build_seconds] = build_accel(g, scene);
        if (g.integrator == "path") return render_path(g, o, scene, *accel, build_seconds);
        if (g.integrator == "sppm") return render_sppm_main(g, o, scene, *accel, build_seconds);
        if (g.integrator == "photons") return render_photons_main(g, o, scene, *accel, build_seconds);
        VplSettings st;
        st.seed = o.seed + 1;
        st.gather = find_choice(std::span<const Choice<VplGather>>(gathers), "gather", g.vpl.gather).make;
        const std::span<const TriangleVertices<float>> mesh(scene.triangles.data() + before_insert,
                                                            scene.triangles.size() - before_insert);
        const VplResult r = render_vpl_cli(scene, *accel, mesh, g.vpl, o.image, st);
        const std::string stem = g.out.substr(0, g.out.size() - 4);
        write_exr(stem + ".exr", r.image, {ExrLayer{"indirect", {"R", "G", "B"}, flatten(r.indirect)}},
                  exr_attributes(g, o, o.image.spp, r.seconds));
        write_png(stem + ".png", r.image, g.exposure, g.tonemap == "reinhard");
        std::printf("rendered %s with %zu VPLs (%s visibility, gather %s) in %.3f s (shooting %.3f s); wrote %s.exr and %s.png\n",
                    scene.name.c_str(), r.vpls, g.vpl.visibility.c_str(), g.vpl.gather.c_str(), r.seconds, r.shooting_seconds,
                    stem.c_str(), stem.c_str());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "glint-render: %s\n", e.what());
        return 1;
    }
}
