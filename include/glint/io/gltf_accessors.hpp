// glint/io/gltf_accessors.hpp: the parts of a glTF 2.0 file that io/gltf.hpp reads before it
// builds a scene: the model through tinygltf, a node's local matrix, and a primitive's
// accessors (positions, normals, texture coordinates, indices, triangles of each primitive
// mode), each checked to lie inside its buffer and to hold what glTF 2.0 says it holds, and a
// texture's decoded image. Errors name the file, the mesh, primitive and accessor, and the
// element.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <tiny_gltf.h>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/tracer/texture.hpp>

namespace glint::detail {

inline tinygltf::Model gltf_read_model(const std::string& path) {
    if (!std::ifstream(path, std::ios::binary)) throw Error("load_gltf(" + path + "): cannot read the file");
    tinygltf::TinyGLTF loader;  // decodes the images (PNG, JPEG) by its own stb_image
    tinygltf::Model model;
    std::string err, warn;
    const bool glb = path.size() >= 4 && path.compare(path.size() - 4, 4, ".glb") == 0;
    const bool ok = glb ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                        : loader.LoadASCIIFromFile(&model, &err, &warn, path);
    if (!ok) throw Error("load_gltf(" + path + "): " + (err.empty() ? "cannot parse the file" : err));
    return model;
}

/// A node's local matrix: `matrix`, or translation * rotation * scale.
inline glm::dmat4 gltf_local_matrix(const tinygltf::Node& n, const std::string& where) {
    glm::dmat4 m(1.0);
    if (n.matrix.size() == 16) {
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) m[c][r] = n.matrix[std::size_t(4 * c + r)];  // column-major
    } else {
        if (n.translation.size() == 3) m = glm::translate(m, glm::dvec3(n.translation[0], n.translation[1], n.translation[2]));
        if (n.rotation.size() == 4)  // glTF stores x, y, z, w
            m *= glm::mat4_cast(glm::normalize(glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2])));
        if (n.scale.size() == 3) m = glm::scale(m, glm::dvec3(n.scale[0], n.scale[1], n.scale[2]));
    }
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) throw Error(where + ": the transform is not finite");
    return m;
}

/// An accessor's bytes, checked to lie inside its buffer view and buffer.
struct GltfElements {
    const unsigned char* data = nullptr;
    std::size_t stride = 0, count = 0;
    int component = 0;
};

inline GltfElements gltf_elements(const tinygltf::Model& model, int index, int type, const std::string& where) {
    const std::string at = where + " accessor " + std::to_string(index);
    if (index < 0 || std::size_t(index) >= model.accessors.size()) throw Error(at + ": no such accessor");
    const tinygltf::Accessor& a = model.accessors[std::size_t(index)];
    if (a.sparse.isSparse) throw Error(at + ": sparse accessors are not supported");
    if (a.type != type)
        throw Error(at + ": expected type " + (type == TINYGLTF_TYPE_VEC3 ? "VEC3" : type == TINYGLTF_TYPE_VEC2 ? "VEC2" : "SCALAR") +
                    ", got type code " + std::to_string(a.type));
    if (a.bufferView < 0 || std::size_t(a.bufferView) >= model.bufferViews.size()) throw Error(at + ": no buffer view");
    const tinygltf::BufferView& v = model.bufferViews[std::size_t(a.bufferView)];
    if (v.buffer < 0 || std::size_t(v.buffer) >= model.buffers.size()) throw Error(at + ": its buffer view has no buffer");
    const std::vector<unsigned char>& b = model.buffers[std::size_t(v.buffer)].data;
    const int stride = a.ByteStride(v);
    const int size = tinygltf::GetComponentSizeInBytes(std::uint32_t(a.componentType)) *
                     tinygltf::GetNumComponentsInType(std::uint32_t(a.type));
    if (stride <= 0 || size <= 0) throw Error(at + ": invalid component type or stride");
    // In bounds: byteOffset + stride (count - 1) + size <= byteLength, written without overflow.
    const bool inside = v.byteOffset <= b.size() && v.byteLength <= b.size() - v.byteOffset &&
                        (a.count == 0 || (a.byteOffset <= v.byteLength && std::size_t(size) <= v.byteLength - a.byteOffset &&
                                          a.count - 1 <= (v.byteLength - a.byteOffset - std::size_t(size)) / std::size_t(stride)));
    if (!inside) throw Error(at + ": " + std::to_string(a.count) + " elements reach past the end of its buffer");
    return {b.data() + v.byteOffset + a.byteOffset, std::size_t(stride), a.count, a.componentType};
}

/// A primitive's POSITION or NORMAL attribute (`what`): finite float VEC3s.
inline std::vector<glm::dvec3> gltf_vec3s(const tinygltf::Model& model, int index, const std::string& where, const std::string& what) {
    const GltfElements e = gltf_elements(model, index, TINYGLTF_TYPE_VEC3, where + ", " + what);
    const std::string at = where + ", " + what + " accessor " + std::to_string(index);
    if (e.component != TINYGLTF_COMPONENT_TYPE_FLOAT) throw Error(at + ": its elements must be floats");
    std::vector<glm::dvec3> out(e.count);
    for (std::size_t i = 0; i < e.count; ++i) {
        float p[3];
        std::memcpy(p, e.data + i * e.stride, sizeof(p));
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            throw Error(at + ": " + (what == "NORMAL" ? "normal " : "position ") + std::to_string(i) + " is not finite");
        out[i] = glm::dvec3(p[0], p[1], p[2]);
    }
    return out;
}

/// A primitive's TEXCOORD_0 attribute: finite VEC2s of floats, or of normalized unsigned
/// bytes or shorts (glTF 2.0, §3.7.2.1).
inline std::vector<glm::dvec2> gltf_vec2s(const tinygltf::Model& model, int index, const std::string& where) {
    const GltfElements e = gltf_elements(model, index, TINYGLTF_TYPE_VEC2, where + ", TEXCOORD_0");
    const std::string at = where + ", TEXCOORD_0 accessor " + std::to_string(index);
    std::vector<glm::dvec2> out(e.count);
    for (std::size_t i = 0; i < e.count; ++i) {
        const unsigned char* p = e.data + i * e.stride;
        if (e.component == TINYGLTF_COMPONENT_TYPE_FLOAT) {
            float f[2];
            std::memcpy(f, p, sizeof(f));
            if (!std::isfinite(f[0]) || !std::isfinite(f[1])) throw Error(at + ": coordinate " + std::to_string(i) + " is not finite");
            out[i] = glm::dvec2(f[0], f[1]);
        } else if (e.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
            out[i] = glm::dvec2(p[0], p[1]) / 255.0;
        } else if (e.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
            std::uint16_t u[2];
            std::memcpy(u, p, sizeof(u));
            out[i] = glm::dvec2(u[0], u[1]) / 65535.0;
        } else {
            throw Error(at + ": its elements must be floats, or normalized unsigned bytes or shorts");
        }
    }
    return out;
}

/// glTF texture `index` (its image decoded by tinygltf, 8 or 16 bits per channel, taken as
/// sRGB as base colour is, glTF 2.0 §3.9.2; its sampler's filter and wrap modes) as a glint
/// texture; `where` names the material.
template <Scalar T>
Texture<T> gltf_texture(const tinygltf::Model& model, int index, const std::string& where) {
    const std::string at = where + ": texture " + std::to_string(index);
    if (index < 0 || std::size_t(index) >= model.textures.size()) throw Error(at + " does not exist");
    const tinygltf::Texture& t = model.textures[std::size_t(index)];
    if (t.source < 0 || std::size_t(t.source) >= model.images.size()) throw Error(at + ": image " + std::to_string(t.source) + " does not exist");
    const tinygltf::Image& im = model.images[std::size_t(t.source)];
    const std::string name = at + " (image " + std::to_string(t.source) + " '" + (im.uri.size() < 200 ? im.uri : im.name) + "')";
    Texture<T> out;
    try {
        out = Texture<T>::from_srgb(im.width, im.height, im.component, im.bits, im.image);
    } catch (const Error& e) {
        throw Error(name + ": " + e.what());
    }
    out.source = im.uri.size() < 200 ? im.uri : "image " + std::to_string(t.source);
    if (t.sampler >= 0 && std::size_t(t.sampler) < model.samplers.size()) {
        const tinygltf::Sampler& s = model.samplers[std::size_t(t.sampler)];
        out.nearest = s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
        const auto wrap = [](int mode) {
            return mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE ? TextureWrap::clamp
                 : mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT ? TextureWrap::mirrored_repeat : TextureWrap::repeat;
        };
        out.wrap_u = wrap(s.wrapS), out.wrap_v = wrap(s.wrapT);
    }
    return out;
}

/// The vertex indices of a primitive (0, 1, ... without an indices accessor), each checked.
inline std::vector<std::uint32_t> gltf_indices(const tinygltf::Model& model, int index, std::size_t vertices, const std::string& where) {
    std::vector<std::uint32_t> out;
    if (index < 0) {
        for (std::size_t i = 0; i < vertices; ++i) out.push_back(std::uint32_t(i));
        return out;
    }
    const GltfElements e = gltf_elements(model, index, TINYGLTF_TYPE_SCALAR, where + ", indices");
    for (std::size_t i = 0; i < e.count; ++i) {
        const unsigned char* p = e.data + i * e.stride;
        std::uint32_t v = 0;
        if (e.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) v = *p;
        else if (e.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) { std::uint16_t s; std::memcpy(&s, p, 2); v = s; }
        else if (e.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) std::memcpy(&v, p, 4);
        else throw Error(where + ", indices accessor " + std::to_string(index) + ": indices must be unsigned integers");
        if (v >= vertices)
            throw Error(where + ", indices accessor " + std::to_string(index) + ": index " + std::to_string(i) + " = " +
                        std::to_string(v) + " is past the " + std::to_string(vertices) + " vertices");
        out.push_back(v);
    }
    return out;
}

/// Triangles of a TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive (glTF 2.0, §3.7.2.1).
inline std::vector<std::array<std::uint32_t, 3>> gltf_triangles(int mode, const std::vector<std::uint32_t>& idx,
                                                                const std::string& where) {
    std::vector<std::array<std::uint32_t, 3>> out;
    if (mode == TINYGLTF_MODE_TRIANGLES || mode == -1) {
        for (std::size_t i = 0; i + 2 < idx.size(); i += 3) out.push_back({idx[i], idx[i + 1], idx[i + 2]});
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (std::size_t i = 0; i + 2 < idx.size(); ++i)
            out.push_back(i % 2 ? std::array{idx[i + 1], idx[i], idx[i + 2]} : std::array{idx[i], idx[i + 1], idx[i + 2]});
    } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
        for (std::size_t i = 1; i + 1 < idx.size(); ++i) out.push_back({idx[0], idx[i], idx[i + 1]});
    } else {
        throw Error(where + ": primitive mode " + std::to_string(mode) +
                    " (points or lines) is not triangles; glint renders triangle meshes only");
    }
    return out;
}

}  // namespace glint::detail
