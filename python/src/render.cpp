// glint.render: the path tracer (tracer/named_render.hpp's render_named, the policies by the
// names glint-render takes) on a built-in scene (tracer/scenes.hpp), a glTF 2.0 file
// (io/gltf.hpp) or a scene JSON that glint-render --export-scene wrote (io/scene_json_read.hpp),
// with glint's default accelerator; the image and the variance of its mean as float32 arrays,
// and on request the render's statistics and the first-hit layers a denoiser takes
// (tracer/first_hit_layers.hpp) in a dict.
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include <glint/io/gltf.hpp>
#include <glint/io/obj.hpp>
#include <glint/io/obj_scene.hpp>
#include <glint/io/scene_json_read.hpp>
#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/first_hit_layers.hpp>
#include <glint/tracer/named_render.hpp>
#include <glint/tracer/scenes.hpp>

#include "arrays.hpp"
#ifdef GLINT_SHARED_INSTANCES
#include "glint_instances.hpp"  // render_named for AnyAccel, compiled once (instances/)
#endif

namespace glint::python {

namespace {

using OptVec = std::optional<std::array<float, 3>>;

/// The camera arguments given; each replaces the scene's.
struct CameraArgs {
    OptVec eye, look_at, up;
    std::optional<float> fov_degrees;
    bool any() const { return eye || look_at || up || fov_degrees; }
};

bool ends_with(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// A glTF scene: its camera, or one framing it where it has none; a sky if nothing emits.
Scene<float> gltf_scene(const std::string& path) {
    GltfScene<float> g = read_gltf<float>(path);
    sky_and_framing(g.scene, g.has_camera);
    return std::move(g.scene);
}

Scene<float> load_scene(const std::string& name) {
    if (ends_with(name, ".gltf") || ends_with(name, ".glb")) return gltf_scene(name);
    if (ends_with(name, ".json")) return read_scene_json<float>(name).scene;
    if (ends_with(name, ".obj")) return obj_scene(load_obj(name), name);  // a sky and a framing camera
    return builtin_scene<float>(name);  // glint::Error listing the names for an unknown one
}

void apply_camera(const CameraArgs& a, Camera<float>& c) {
    auto vec = [](const std::array<float, 3>& v) { return Vec3f(v[0], v[1], v[2]); };
    if (a.eye) c.eye = vec(*a.eye);
    if (a.look_at) c.target = vec(*a.look_at);
    if (a.up) c.up = vec(*a.up);
    if (a.fov_degrees) {
        if (!(*a.fov_degrees > 0.0f && *a.fov_degrees < 180.0f))
            throw Error("render: fov = " + std::to_string(*a.fov_degrees) + " degrees is outside (0, 180)");
        c.fov_y = *a.fov_degrees * pi<float> / 180.0f;
    }
    const Vec3f w = c.target - c.eye;
    if (!(glm::length(w) > 0.0f)) throw Error("render: eye and look_at must differ");
    if (!(glm::length(glm::cross(w, c.up)) > 0.0f)) throw Error("render: up must not be parallel to look_at - eye");
}

py::array_t<float> to_array(const Image<Rgb<float>>& img) {
    py::array_t<float> out({py::ssize_t(img.height), py::ssize_t(img.width), py::ssize_t(3)});
    float* p = out.mutable_data();
    for (const Rgb<float>& c : img.pixels) *p++ = c[0], *p++ = c[1], *p++ = c[2];
    return out;
}

/// Checks every argument before any file is read: the sizes, then the policies' names.
NamedRender<float> settings(int width, int height, int spp, std::uint64_t seed, int threads, int max_depth,
                            const std::string& roulette, const std::string& direct, const std::string& sampler) {
    auto in = [](const char* what, long long v, long long lo, long long hi) {
        if (v < lo || v > hi)
            throw Error(std::string("render: ") + what + " = " + std::to_string(v) + " is outside [" + std::to_string(lo) +
                        ", " + std::to_string(hi) + "]");
    };
    in("width", width, 1, 16384), in("height", height, 1, 16384), in("spp", spp, 1, 1 << 20);
    in("threads", threads, 0, 4096), in("max_depth", max_depth, 1, 1 << 24);
    NamedRender<float> o;
    o.image.width = width, o.image.height = height, o.image.spp = spp, o.image.threads = threads;
    o.tracer.max_depth = max_depth;
    o.seed = seed;
    o.roulette = roulette, o.direct = direct, o.sampler = sampler;
    check_names(o);
    return o;
}

/// What render() returns besides the image and its variance, when asked.
struct Extras {
    bool stats = false, aov = false;
};

py::array_t<float> to_array(const Image<float>& img) {
    py::array_t<float> out({py::ssize_t(img.height), py::ssize_t(img.width)});
    std::copy(img.pixels.begin(), img.pixels.end(), out.mutable_data());
    return out;
}

py::dict extras_dict(const RenderResult& r, const std::optional<FirstHitImages>& layers) {
    py::dict d;
    d["seconds"] = r.seconds, d["rays"] = r.rays, d["paths"] = r.paths, d["capped_walks"] = r.capped_walks;
    if (layers) d["albedo"] = to_array(layers->albedo), d["normal"] = to_array(layers->normal), d["depth"] = to_array(layers->depth);
    return d;
}

py::tuple render(const std::string& scene_name, int width, int height, int spp, std::uint64_t seed, int threads,
                 int max_depth, const std::string& roulette, const std::string& direct, const std::string& sampler,
                 const CameraArgs& cam, const std::optional<std::string>& insert, Extras extras) {
    const NamedRender<float> o = settings(width, height, spp, seed, threads, max_depth, roulette, direct, sampler);
    if (insert && !scene_name.starts_with("cornell"))
        throw Error("render: insert_mesh puts a mesh on the Cornell box's floor; scene '" + scene_name + "' is not one");
    RenderResult r;
    std::optional<FirstHitImages> layers;
    {
        py::gil_scoped_release release;
        Scene<float> scene = load_scene(scene_name);
        apply_camera(cam, scene.camera);
        if (insert)
            insert_mesh<float>(scene, load_obj(*insert).triangles,
                               Material<float>::lambertian(Rgb<float>(0.725f, 0.71f, 0.68f)), cornell_mesh_placement<float>());
        const DefaultAccel accel(std::span<const TriangleVertices<float>>(scene.triangles));
        r = render_named(scene, any_accel_view(accel), o);
        if (extras.aov) layers = render_first_hit_named(scene, any_accel_view(accel), o);
    }
    if (!extras.stats && !extras.aov) return py::make_tuple(to_array(r.image), to_array(r.variance));
    return py::make_tuple(to_array(r.image), to_array(r.variance), extras_dict(r, layers));
}

}  // namespace

void bind_render(py::module_& m) {
    m.def(
        "render",
        [](const std::string& scene, int width, int height, int spp, std::uint64_t seed, int threads, int max_depth,
           const std::string& roulette, const std::string& direct, const std::string& sampler, OptVec eye, OptVec look_at,
           OptVec up, std::optional<float> fov, std::optional<std::string> insert_mesh, bool stats, bool aov) {
            return render(scene, width, height, spp, seed, threads, max_depth, roulette, direct, sampler,
                          CameraArgs{eye, look_at, up, fov}, insert_mesh, Extras{stats, aov});
        },
        py::arg("scene") = "cornell", py::arg("width") = 256, py::arg("height") = 256, py::arg("spp") = 16,
        py::arg("seed") = 0, py::arg("threads") = 0, py::arg("max_depth") = 1024, py::arg("roulette") = "throughput",
        py::arg("direct") = "mis", py::arg("sampler") = "halton", py::arg("eye") = py::none(),
        py::arg("look_at") = py::none(), py::arg("up") = py::none(), py::arg("fov") = py::none(),
        py::arg("insert_mesh") = py::none(), py::arg("stats") = false, py::arg("aov") = false,
        "Path-traces `scene` (a built-in name such as 'cornell', a .gltf/.glb file, an .obj (+.mtl) file, or\n"
        "a .json file that glint-render --export-scene wrote) at width x height with spp samples per pixel; returns\n"
        "(image, variance), float32 arrays (height, width, 3): the mean radiance per pixel and the variance\n"
        "of that mean. roulette, direct and sampler take glint-render's names; eye, look_at, up (3 numbers)\n"
        "and fov (degrees) replace the scene's camera; insert_mesh puts an OBJ on the Cornell box's floor.\n"
        "threads: 0 for every core. stats or aov: a third element, a dict with the render's 'seconds',\n"
        "'rays', 'paths' and 'capped_walks', and with aov the first-hit layers a denoiser takes: 'albedo'\n"
        "(height, width, 3), 'normal' (height, width, 3) and 'depth' (height, width), averaged over the\n"
        "same camera rays. Every argument is checked before any file is read (glint.Error).");
}

}  // namespace glint::python
