// The Python module glint: glint's version, its exception, and the bindings of io.cpp
// (load_obj, load_gltf), bvh.cpp (MeshBvh), render.cpp (render) and halton.cpp (halton).
#include <pybind11/pybind11.h>

#include <glint/core/error.hpp>
#include <glint/version.hpp>

#include "arrays.hpp"

PYBIND11_MODULE(glint, m) {
    m.doc() = "glint: rendering algorithms (a header-only C++20 toolkit) from Python";
    m.attr("__version__") = glint::version_string;
    // glint::Error arrives as glint.Error (a RuntimeError) with the same message.
    pybind11::register_exception<glint::Error>(m, "Error", PyExc_RuntimeError);
    glint::python::bind_io(m);
    glint::python::bind_bvh(m);
    glint::python::bind_render(m);
    glint::python::bind_halton(m);
}
