// The Python module's shared pieces: the checks of the numpy arrays it reads in place (dtype,
// shape, C order; a glint::Error naming the argument otherwise) and the entry points of each
// source file, which module.cpp calls.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/pybind11.h>

#include <glint/core/error.hpp>

namespace glint::python {

namespace py = pybind11;

/// The (n, 3) C-ordered array `o` of 4-byte elements of numpy kind `kind` ('f' float32, 'i'
/// int32, 'u' uint32; `kinds` lists the accepted ones), as the array itself (kept alive by
/// the caller) and its row count. `what` names the argument in the error.
inline py::array rows3(const py::object& o, const std::string& what, const std::string& kinds, std::size_t& n) {
    const std::string want = kinds == "f" ? "float32" : "int32 or uint32";
    if (!py::isinstance<py::array>(o))
        throw Error(what + ": expected a numpy array of shape (n, 3) and dtype " + want + ", got " +
                    std::string(py::str(o.get_type().attr("__name__"))));
    const auto a = py::reinterpret_borrow<py::array>(o);
    const char kind = a.dtype().kind();
    if (kinds.find(kind) == std::string::npos || a.dtype().itemsize() != 4)
        throw Error(what + ": dtype " + std::string(py::str(a.dtype())) + ", expected " + want +
                    " (convert with numpy.asarray(x, dtype=numpy." + (kinds == "f" ? "float32" : "uint32") + "))");
    if (a.ndim() != 2 || a.shape(1) != 3)
        throw Error(what + ": shape " + std::string(py::str(o.attr("shape"))) + ", expected (n, 3)");
    if (!(a.flags() & py::array::c_style))
        throw Error(what + ": not C-contiguous (use numpy.ascontiguousarray)");
    n = std::size_t(a.shape(0));
    return a;
}

void bind_io(py::module_& m);
void bind_bvh(py::module_& m);
void bind_render(py::module_& m);
void bind_halton(py::module_& m);

}  // namespace glint::python
