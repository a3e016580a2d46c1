// glint/io/obj_scan.hpp: what io/obj.hpp checks in an OBJ and MTL text before tinyobjloader
// parses it (tinyobjloader reads what it cannot parse as 0 and keeps a face's vertex count in
// an unsigned char): the lines as tinyobjloader splits them, finite numbers, face indices that
// name existing vertices, polygons of more than 255 vertices written as fans, the MTL's Kd,
// Ks, Ke, Ns and Ni; and the MTL lookup next to the OBJ. Errors name the file, the line and
// the value. io/obj.hpp's header comment lists the rules.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <tiny_obj_loader.h>

#include <glint/core/error.hpp>

namespace glint {

namespace detail {

inline std::vector<std::string_view> obj_tokens(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
        const std::size_t b = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
        if (i > b) out.push_back(line.substr(b, i - b));
    }
    return out;
}

/// Reads one line ending in "\n", "\r\n" or a lone "\r" (tinyobjloader splits lines at
/// all three, so the checks must see the same lines it parses). False at end of input.
inline bool obj_getline(std::istream& in, std::string& line) {
    line.clear();
    std::streambuf* buf = in.rdbuf();
    for (;;) {
        const int c = buf->sbumpc();
        if (c == std::char_traits<char>::eof()) {
            if (line.empty()) in.setstate(std::ios::eofbit);
            return !line.empty();
        }
        if (c == '\n') return true;
        if (c == '\r') {
            if (buf->sgetc() == '\n') buf->sbumpc();
            return true;
        }
        line += static_cast<char>(c);
    }
}

/// A number that is finite as a float, or glint::Error naming `where` and the token.
inline float obj_number(std::string_view tok, const std::string& where) {
    const std::string s(tok);
    char* end = nullptr;
    const double x = std::strtod(s.c_str(), &end);
    if (end == s.c_str() || *end) throw Error(where + ": '" + s + "' is not a number");
    if (!std::isfinite(x) || !std::isfinite(static_cast<float>(x)))
        throw Error(where + ": '" + s + "' is not a finite number");
    return static_cast<float>(x);
}

/// The OBJ text with every polygon of more than 255 vertices written as a fan of triangles,
/// the source line of each face in file order, and the checks of the header comment.
struct ObjScan {
    std::string text;
    std::vector<std::uint32_t> face_line;
};

struct ObjFaceIndex {
    std::uint32_t line;
    long index;  // as written (1-based, or negative = relative)
};

inline void obj_check_indices(const std::string& file, const std::vector<ObjFaceIndex>& positive, long nv) {
    for (const ObjFaceIndex& f : positive)
        if (f.index > nv)
            throw Error(file + ":" + std::to_string(f.line) + ": face refers to vertex " + std::to_string(f.index) +
                        ", but the file defines " + std::to_string(nv) + " vertices");
}

/// Checks one `f` line's vertex tokens; returns the positive indices for the end-of-file check.
inline void obj_scan_face(const std::vector<std::string_view>& tok, const std::string& where, std::uint32_t line,
                          long nv, std::vector<ObjFaceIndex>& positive) {
    if (tok.size() < 4)
        throw Error(where + ": a face needs at least 3 vertices, this one has " + std::to_string(tok.size() - 1));
    for (std::size_t k = 1; k < tok.size(); ++k) {
        const std::string s(tok[k].substr(0, tok[k].find('/')));
        char* end = nullptr;
        const long i = std::strtol(s.c_str(), &end, 10);
        if (end == s.c_str() || *end) throw Error(where + ": face vertex '" + std::string(tok[k]) + "' is not an index");
        if (i < -std::numeric_limits<int>::max() || i > std::numeric_limits<int>::max())  // tinyobjloader reads an int
            throw Error(where + ": face vertex index " + s + " is out of range");
        if (i == 0) throw Error(where + ": face vertex index 0 (OBJ indices start at 1)");
        if (i < 0 && nv + i < 0)
            throw Error(where + ": face vertex " + s + " refers " + std::to_string(-i) + " vertices back, but only " +
                        std::to_string(nv) + " vertices are defined before this line");
        if (i > 0) positive.push_back({line, i});
    }
}

inline ObjScan obj_scan(const std::string& file, std::istream& in) {
    ObjScan scan;
    std::vector<ObjFaceIndex> positive;
    long nv = 0;
    std::string raw;
    std::uint32_t line = 0;
    while (obj_getline(in, raw)) {
        ++line;
        const std::vector<std::string_view> tok = obj_tokens(raw);
        const std::string where = file + ":" + std::to_string(line);
        if (!tok.empty() && tok[0] == "v") {
            if (tok.size() < 4) throw Error(where + ": a vertex needs 3 coordinates");
            for (std::size_t k = 1; k <= 3; ++k) obj_number(tok[k], where + ": vertex coordinate");
            ++nv;
        } else if (!tok.empty() && tok[0] == "f") {
            obj_scan_face(tok, where, line, nv, positive);
            if (tok.size() - 1 > 255) {  // tinyobjloader would wrap the count at 256
                for (std::size_t k = 2; k + 1 < tok.size(); ++k) {
                    scan.text.append("f ").append(tok[1]).append(" ").append(tok[k]).append(" ").append(tok[k + 1]);
                    scan.text += '\n';
                    scan.face_line.push_back(line);
                }
                continue;
            }
            scan.face_line.push_back(line);
        }
        scan.text.append(raw) += '\n';
    }
    obj_check_indices(file, positive, nv);
    return scan;
}

/// Checks the Kd, Ks, Ke, Ns and Ni lines of an MTL text (see the header comment).
inline void mtl_validate(const std::string& file, std::istream& in) {
    std::string raw, material = "(before any newmtl)";
    std::uint32_t line = 0;
    while (obj_getline(in, raw)) {
        ++line;
        const std::vector<std::string_view> tok = obj_tokens(raw);
        if (tok.empty()) continue;
        if (tok[0] == "newmtl" && tok.size() > 1) material = std::string(tok[1]);
        const bool colour = tok[0] == "Kd" || tok[0] == "Ks" || tok[0] == "Ke";
        if (!colour && tok[0] != "Ns" && tok[0] != "Ni") continue;
        const std::string where = file + ":" + std::to_string(line) + ": material '" + material + "' " + std::string(tok[0]);
        if (tok.size() < 2) throw Error(where + " has no value");
        for (std::size_t k = 1; k < std::min<std::size_t>(tok.size(), colour ? 4 : 2); ++k) {
            const float v = obj_number(tok[k], where);
            if (v < 0.0f || (tok[0] == "Ni" && v == 0.0f))
                throw Error(where + " = " + std::string(tok[k]) + (v < 0.0f ? " is negative" : " is not positive"));
        }
    }
}

/// tinyobjloader's MTL lookup next to the OBJ, with glint's checks and a warning for a
/// missing file.
class ObjMaterialReader : public tinyobj::MaterialReader {
public:
    explicit ObjMaterialReader(std::string dir) : dir_(std::move(dir)) {}
    bool operator()(const std::string& id, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* names, std::string* warn, std::string* err) override {
        const std::string file = dir_ + id;
        std::ifstream f(file, std::ios::binary);
        if (!f) {
            warnings.push_back("material file '" + file + "' not found; its materials render as default grey");
            return false;
        }
        std::stringstream text;
        text << f.rdbuf();
        mtl_validate(file, text);
        text.clear();
        text.seekg(0);
        tinyobj::LoadMtl(names, materials, &text, warn, err);
        return true;
    }
    std::vector<std::string> warnings;

private:
    std::string dir_;
};

}  // namespace detail
}  // namespace glint
