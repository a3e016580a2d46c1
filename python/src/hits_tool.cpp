// glint_python_hits: the C++ side of the Python module's comparisons. Reads a mesh and rays
// from a file the tests write (python/tests/hits_io.py), traces every ray with MeshBvh's own
// closest_hit and any_hit in a plain single-threaded loop, writes the hits and prints the
// CPU seconds of each loop (the thread's own, so that a shared core's other work is left out):
//
//   glint_python_hits RAYS.bin HITS.bin   ->   "closest_seconds S any_seconds S rays N"
//
// RAYS.bin: "GLNTRAYS", then uint64 vertex, triangle and ray counts, float tmin and tmax,
// then vertices (float32 x 3), indices (uint32 x 3), origins and directions (float32 x 3).
// HITS.bin: t, u, v (float32 per ray; inf, 0, 0 on a miss), id (int32, -1 on a miss), any
// (uint8 per ray).
#include <cstdint>
#include <ctime>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <glint/tracer/accelerator_choices.hpp>
#include <glint/trees/mesh_bvh.hpp>

using namespace glint;

namespace {

template <class T>
std::vector<T> read_array(std::ifstream& in, std::uint64_t n, const char* what) {
    std::vector<T> v(n);
    if (!in.read(reinterpret_cast<char*>(v.data()), std::streamsize(n * sizeof(T))))
        throw Error(std::string("glint_python_hits: the file ends inside the ") + what);
    return v;
}

template <class T>
void write_array(std::ofstream& out, const std::vector<T>& v) {
    out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
}

/// This thread's CPU seconds (the time it ran: on a shared core, waiting for the core is left out).
double thread_seconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

int run(const std::string& in_path, const std::string& out_path) {
    std::ifstream in(in_path, std::ios::binary);
    char magic[8];
    std::uint64_t count[3];
    float interval[2];
    if (!in.read(magic, 8) || std::memcmp(magic, "GLNTRAYS", 8) != 0 || !in.read(reinterpret_cast<char*>(count), sizeof count) ||
        !in.read(reinterpret_cast<char*>(interval), sizeof interval))
        throw Error("glint_python_hits: " + in_path + " is not a rays file");
    const auto vertices = read_array<float>(in, 3 * count[0], "vertices");
    const auto indices = read_array<std::uint32_t>(in, 3 * count[1], "indices");
    const auto origins = read_array<float>(in, 3 * count[2], "origins");
    const auto directions = read_array<float>(in, 3 * count[2], "directions");
    const DefaultAccel bvh(IndexedMesh<float>{vertices.data(), count[0], 3 * sizeof(float), indices.data(), count[1]});
    const std::size_t n = count[2];
    auto ray = [&](std::size_t i) {
        const float *o = &origins[3 * i], *d = &directions[3 * i];
        return Ray<float>{Vec3f(o[0], o[1], o[2]), Vec3f(d[0], d[1], d[2]), interval[0], interval[1]};
    };
    std::vector<StoreHit<float>> hits(n);
    double start = thread_seconds();
    for (std::size_t i = 0; i < n; ++i) bvh.closest_hit(ray(i), hits[i]);
    const double closest_seconds = thread_seconds() - start;
    std::vector<std::uint8_t> any(n);
    start = thread_seconds();
    for (std::size_t i = 0; i < n; ++i) any[i] = bvh.any_hit(ray(i)) ? 1 : 0;
    const double any_seconds = thread_seconds() - start;
    std::vector<float> t(n), u(n), v(n);
    std::vector<std::int32_t> id(n);
    for (std::size_t i = 0; i < n; ++i) {
        const bool hit = hits[i].id != std::numeric_limits<std::uint32_t>::max();
        t[i] = hits[i].t, u[i] = hit ? hits[i].u : 0.0f, v[i] = hit ? hits[i].v : 0.0f;
        id[i] = hit ? std::int32_t(hits[i].id) : -1;
    }
    std::ofstream out(out_path, std::ios::binary);
    write_array(out, t), write_array(out, u), write_array(out, v), write_array(out, id), write_array(out, any);
    if (!out) throw Error("glint_python_hits: cannot write " + out_path);
    std::printf("closest_seconds %.9g any_seconds %.9g rays %zu\n", closest_seconds, any_seconds, n);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: glint_python_hits RAYS.bin HITS.bin\n");
        return 2;
    }
    try {
        return run(argv[1], argv[2]);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
