// benchmarks/support/obj_reader.hpp: the benchmarks' minimal OBJ reader (bench_trees,
// bench_user_meshes).
#pragma once

#include <cstddef>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include "tree_scenes.hpp"  // Mesh<T>

namespace glint::bench {

/// Minimal OBJ reader: `v x y z` and `f i j k ...` (i, i/t, i//n, i/t/n, negative indices),
/// polygons fan-triangulated; every other line is ignored.
inline Mesh<float> read_obj(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot open mesh '" + path + "'");
    std::vector<Vec3f> v;
    Mesh<float> m;
    std::string line;
    int lineno = 0;
    while (std::getline(in, line)) {
        ++lineno;
        std::istringstream ss(line);
        std::string tag;
        ss >> tag;
        if (tag == "v") {
            Vec3f p;
            if (!(ss >> p.x >> p.y >> p.z))
                throw Error(path + ":" + std::to_string(lineno) + ": expected 'v x y z'");
            v.push_back(p);
        } else if (tag == "f") {
            std::vector<std::size_t> idx;
            std::string tok;
            while (ss >> tok) {
                long i = 0;
                try {
                    i = std::stol(tok.substr(0, tok.find('/')));
                } catch (const std::exception&) {
                    throw Error(path + ":" + std::to_string(lineno) + ": bad face index '" + tok + "'");
                }
                const long k = i > 0 ? i - 1 : long(v.size()) + i;
                if (i == 0 || k < 0 || k >= long(v.size()))
                    throw Error(path + ":" + std::to_string(lineno) + ": face index " + std::to_string(i) +
                                " outside the " + std::to_string(v.size()) + " vertices read so far");
                idx.push_back(std::size_t(k));
            }
            if (idx.size() < 3) throw Error(path + ":" + std::to_string(lineno) + ": a face needs 3 vertices");
            for (std::size_t j = 1; j + 1 < idx.size(); ++j) m.push_back({v[idx[0]], v[idx[j]], v[idx[j + 1]]});
        }
    }
    if (m.empty()) throw Error("'" + path + "' has no faces");
    return m;
}

}  // namespace glint::bench
