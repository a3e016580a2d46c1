// glint/io/image_file.hpp: an image file (PNG, JPEG, BMP, TGA, ...: what stb_image reads) as
// a texture (tracer/texture.hpp), its texels taken as sRGB. The file is decoded by tinygltf's
// image loader, the copy of stb_image that glint::io already links (TinyGLTF::TinyGLTF), so a
// program needs no stb_image implementation of its own.
//
//   Texture<float> t = glint::load_texture<float>("wood.png");  // throws glint::Error
#pragma once

#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include <glint/core/error.hpp>
#include <glint/tracer/texture.hpp>

namespace glint {

/// The image file `path` as a texture (linear texels from sRGB, bilinear, repeating);
/// glint::Error naming the file where it cannot be read or decoded.
template <Scalar T>
Texture<T> load_texture(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error("load_texture(" + path + "): cannot read the file");
    const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (bytes.empty() || bytes.size() > std::size_t(std::numeric_limits<int>::max()))
        throw Error("load_texture(" + path + "): " + std::to_string(bytes.size()) + " bytes is not an image file's size");
    tinygltf::Image image;
    std::string err, warn;
    if (!tinygltf::LoadImageData(&image, 0, &err, &warn, 0, 0, bytes.data(), int(bytes.size()), nullptr))
        throw Error("load_texture(" + path + "): " + (err.empty() ? "cannot decode the image" : err));
    try {
        Texture<T> t = Texture<T>::from_srgb(image.width, image.height, image.component, image.bits, image.image);
        t.source = path;
        return t;
    } catch (const Error& e) {
        throw Error("load_texture(" + path + "): " + e.what());
    }
}

}  // namespace glint
