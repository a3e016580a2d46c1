// glint.MeshBvh: glint's default accelerator (an 8-wide BVH with Moller-Trumbore leaves,
// tracer/accelerator_choices.hpp's DefaultAccel) over the user's numpy arrays, queried with
// arrays of rays. The tree is built from the arrays in place (IndexedMesh: no copy); it keeps
// its own triangle records, and the module keeps references to the two arrays for the
// geometric normals of hits (computed here from the hit triangle's vertices, in their order:
// normalize(cross(v1 - v0, v2 - v0)); the C++ hit has no normal). The queries release the GIL
// and share the rays among threads in blocks (core/parallel.hpp).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>

#include <glint/core/parallel.hpp>
#include <glint/tracer/accelerator_choices.hpp>
#include <glint/trees/mesh_bvh.hpp>

#include "arrays.hpp"

namespace glint::python {

namespace {

/// Rays per block a worker takes at a time.
constexpr std::size_t ray_block = 4096;

/// Calls f(begin, end) for blocks of [0, n) on `threads` workers (0: every core), without the GIL.
template <class F>
void for_each_block(std::size_t n, int threads, const F& f) {
    if (threads < 0) throw Error("threads = " + std::to_string(threads) + " is negative (0: every core)");
    const int blocks = int((n + ray_block - 1) / ray_block);
    py::gil_scoped_release release;
    detail::parallel_blocks(blocks, threads, [&](std::atomic<int>& next) {
        for (int b = next++; b < blocks; b = next++) {
            f(std::size_t(b) * ray_block, std::min(n, (std::size_t(b) + 1) * ray_block));
        }
    });
}

Vec3f row(const float* a, std::size_t i) { return {a[3 * i], a[3 * i + 1], a[3 * i + 2]}; }

/// A query's rays: the two arrays (held while tracing), checked, and their row count.
struct Rays {
    py::array origins, directions;
    std::size_t n = 0;
    const float *origin_rows = nullptr, *direction_rows = nullptr;

    Rays(const py::object& o, const py::object& d, float tmin, float tmax) {
        std::size_t nd = 0;
        origins = rows3(o, "origins", "f", n);
        directions = rows3(d, "directions", "f", nd);
        if (n != nd) throw Error("origins has " + std::to_string(n) + " rows but directions has " + std::to_string(nd));
        if (std::isnan(tmin) || std::isnan(tmax) || tmin > tmax)
            throw Error("tmin = " + std::to_string(tmin) + ", tmax = " + std::to_string(tmax) + ": need tmin <= tmax");
        origin_rows = static_cast<const float*>(origins.data());
        direction_rows = static_cast<const float*>(directions.data());
    }
    Ray<float> ray(std::size_t i, float tmin, float tmax) const { return {row(origin_rows, i), row(direction_rows, i), tmin, tmax}; }
};

/// Rays per stream query (MeshBvh's packets of 16 where the rays are coherent), held on the
/// stack with their hits.
constexpr std::size_t stream_chunk = 256;

/// Calls f(rays, first) on the rays [begin, end) of r, stream_chunk at a time, `first` the
/// index of rays[0].
template <class F>
void for_each_chunk(const Rays& r, std::size_t begin, std::size_t end, float tmin, float tmax, const F& f) {
    Ray<float> rays[stream_chunk];
    for (std::size_t first = begin; first < end; first += stream_chunk) {
        const std::size_t m = std::min(stream_chunk, end - first);
        for (std::size_t k = 0; k < m; ++k) rays[k] = r.ray(first + k, tmin, tmax);
        f(std::span<const Ray<float>>(rays, m), first);
    }
}

class PyMeshBvh {
public:
    PyMeshBvh(const py::object& vertices, const py::object& indices, unsigned build_threads) {
        std::size_t nv = 0, nt = 0;
        vertices_ = rows3(vertices, "MeshBvh: vertices", "f", nv);
        indices_ = rows3(indices, "MeshBvh: indices", "iu", nt);
        const auto* idx = static_cast<const std::uint32_t*>(indices_.data());
        if (indices_.dtype().kind() == 'i')
            for (std::size_t k = 0; k < 3 * nt; ++k)
                if (std::int32_t(idx[k]) < 0)
                    throw Error("MeshBvh: indices: triangle " + std::to_string(k / 3) + " has vertex index " +
                                std::to_string(std::int32_t(idx[k])) + " (negative)");
        mesh_ = IndexedMesh<float>{vertices_.data(), nv, 3 * sizeof(float), idx, nt};
        try {
            mesh_.check();
        } catch (const Error& e) {
            throw Error(std::string("MeshBvh: indices: ") + e.what());
        }
        BvhBuildOptions opt;
        opt.threads = build_threads;
        py::gil_scoped_release release;
        bvh_ = std::make_unique<const DefaultAccel>(mesh_, opt);
    }

    py::dict closest_hit(const py::object& origins, const py::object& directions, float tmin, float tmax, int threads,
                         bool normals) const {
        const Rays r(origins, directions, tmin, tmax);
        const std::size_t n = r.n;
        const auto k = static_cast<py::ssize_t>(n);
        py::array_t<float> t(k), u(k), v(k);
        py::array_t<std::int32_t> id(k);
        py::array_t<float> normal({k, py::ssize_t(3)});
        float *pt = t.mutable_data(), *pu = u.mutable_data(), *pv = v.mutable_data(), *pn = normal.mutable_data();
        std::int32_t* pid = id.mutable_data();
        for_each_block(n, threads, [&](std::size_t begin, std::size_t end) {
            for_each_chunk(r, begin, end, tmin, tmax, [&](std::span<const Ray<float>> rays, std::size_t first) {
                StoreHit<float> hits[stream_chunk];  // a miss leaves t = inf, u = v = 0 and id = -1 as int32
                bvh_->closest_hit(rays, std::span<StoreHit<float>>(hits, rays.size()));
                for (std::size_t k = 0; k < rays.size(); ++k) {
                    const std::size_t i = first + k;
                    pt[i] = hits[k].t, pu[i] = hits[k].u, pv[i] = hits[k].v, pid[i] = std::int32_t(hits[k].id);
                }
            });
            if (normals) write_normals(pid + begin, pn + 3 * begin, end - begin);
        });
        if (!normals) std::fill_n(pn, 3 * n, 0.0f);
        return py::dict(py::arg("t") = t, py::arg("u") = u, py::arg("v") = v, py::arg("id") = id, py::arg("normal") = normal);
    }

    py::array_t<bool> any_hit(const py::object& origins, const py::object& directions, float tmin, float tmax, int threads) const {
        const Rays r(origins, directions, tmin, tmax);
        py::array_t<bool> out(py::ssize_t(r.n));
        bool* p = out.mutable_data();
        for_each_block(r.n, threads, [&](std::size_t begin, std::size_t end) {
            for_each_chunk(r, begin, end, tmin, tmax, [&](std::span<const Ray<float>> rays, std::size_t first) {
                bvh_->any_hit(rays, std::span<bool>(p + first, rays.size()));
            });
        });
        return out;
    }

    std::size_t vertex_count() const { return mesh_.vertex_count; }
    std::size_t triangle_count() const { return mesh_.triangle_count; }
    std::size_t bytes() const { return bvh_->total_bytes(); }
    std::string isa() const { return std::string(isa_name(bvh_->isa())); }

private:
    /// The normals of `n` hits (ids, -1 for a miss) in a pass of their own after the traversal,
    /// with the index rows fetched 16 hits ahead and the vertex rows 8 ahead: the hits' random
    /// triangles miss the cache on large meshes, and inside the traversal loop the loads
    /// cost 1.5 times as much (bunny, 10^6 rays).
    void write_normals(const std::int32_t* id, float* out, std::size_t n) const {
        const auto* v = static_cast<const float*>(mesh_.positions);
        for (std::size_t i = 0; i < n; ++i) {
            if (i + 16 < n && id[i + 16] >= 0) __builtin_prefetch(mesh_.indices + 3 * std::size_t(id[i + 16]));
            if (i + 8 < n && id[i + 8] >= 0)
                for (int k = 0; k < 3; ++k) __builtin_prefetch(v + 3 * std::size_t(mesh_.indices[3 * std::size_t(id[i + 8]) + k]));
            const Vec3f g = id[i] >= 0 ? geometric_normal(std::uint32_t(id[i])) : Vec3f(0.0f);
            out[3 * i] = g.x, out[3 * i + 1] = g.y, out[3 * i + 2] = g.z;
        }
    }
    /// Read from the (n, 3) float32 rows directly: through IndexedMesh::vertex's copies the
    /// loads waited on the stores (normals took 1.3 times as long on the bunny).
    Vec3f geometric_normal(std::uint32_t id) const {
        const auto* v = static_cast<const float*>(mesh_.positions);
        const std::uint32_t* tri = mesh_.indices + 3 * std::size_t(id);
        const Vec3f a = row(v, tri[0]), b = row(v, tri[1]), c = row(v, tri[2]);
        const Vec3f n = glm::cross(b - a, c - a);
        return n * (1.0f / std::sqrt(glm::dot(n, n)));
    }

    py::array vertices_, indices_;  // the user's arrays, read by geometric_normal()
    IndexedMesh<float> mesh_;
    std::unique_ptr<const DefaultAccel> bvh_;
};

}  // namespace

void bind_bvh(py::module_& m) {
    py::class_<PyMeshBvh>(m, "MeshBvh",
                          "glint's fast ray accelerator (8-wide BVH) over a triangle mesh given as numpy arrays:\n"
                          "vertices (n, 3) float32 and indices (m, 3) int32 or uint32, both C-contiguous. The arrays\n"
                          "are read in place and kept (for the hits' normals): do not change them afterwards.")
        .def(py::init<const py::object&, const py::object&, unsigned>(), py::arg("vertices"), py::arg("indices"),
             py::arg("build_threads") = 1)
        .def("closest_hit", &PyMeshBvh::closest_hit, py::arg("origins"), py::arg("directions"), py::arg("tmin") = 0.0f,
             py::arg("tmax") = std::numeric_limits<float>::infinity(), py::arg("threads") = 0, py::arg("normals") = true,
             "The nearest hit of each ray o + t d with t in (tmin, tmax); origins and directions (k, 3) float32\n"
             "(directions need not be unit: t is in units of |d|). Returns a dict of arrays: t (inf on a miss),\n"
             "u, v (barycentrics of vertices 1 and 2), id (the triangle's row in indices, -1 on a miss) and\n"
             "normal (k, 3): the unit geometric normal normalize(cross(v1 - v0, v2 - v0)), 0 on a miss (and\n"
             "everywhere with normals=False, which skips computing them).\n"
             "threads: 0 for every core. The GIL is released while tracing.")
        .def("any_hit", &PyMeshBvh::any_hit, py::arg("origins"), py::arg("directions"), py::arg("tmin") = 0.0f,
             py::arg("tmax") = std::numeric_limits<float>::infinity(), py::arg("threads") = 0,
             "Whether each ray hits any triangle with t in (tmin, tmax) (shadow rays): a bool array.")
        .def_property_readonly("vertex_count", &PyMeshBvh::vertex_count)
        .def_property_readonly("triangle_count", &PyMeshBvh::triangle_count)
        .def_property_readonly("bytes", &PyMeshBvh::bytes, "node and triangle-record bytes")
        .def_property_readonly("isa", &PyMeshBvh::isa, "the traversal kernels chosen for this CPU");
}

}  // namespace glint::python
