// glint.halton: the first n points (from `start`) of a (randomized) Halton sequence as an
// (n, dims) float64 array (sampling/halton.hpp).
#include <cstdint>
#include <string>

#include <glint/sampling/halton.hpp>

#include "arrays.hpp"

namespace glint::python {

namespace {

HaltonRandomization randomization(const std::string& name) {
    for (auto r : {HaltonRandomization::none, HaltonRandomization::cranley_patterson,
                   HaltonRandomization::digit_permutation, HaltonRandomization::owen})
        if (name == short_name(r)) return r;
    throw Error("halton: unknown randomization '" + name + "' (none, cp, perm, owen)");
}

py::array_t<double> halton(long long n, long long dims, std::uint64_t seed, const std::string& random, std::uint64_t start) {
    if (n < 0) throw Error("halton: n = " + std::to_string(n) + " is negative");
    if (dims < 1 || dims > (long long)prime_count)
        throw Error("halton: dims = " + std::to_string(dims) + " is outside [1, " + std::to_string(prime_count) + "]");
    const Halton<double> h(std::size_t(dims), randomization(random), seed);
    py::array_t<double> out({py::ssize_t(n), py::ssize_t(dims)});
    double* p = out.mutable_data();
    py::gil_scoped_release release;
    for (long long i = 0; i < n; ++i)
        for (long long k = 0; k < dims; ++k) *p++ = h.sample(start + std::uint64_t(i), std::size_t(k));
    return out;
}

}  // namespace

void bind_halton(py::module_& m) {
    m.def("halton", &halton, py::arg("n"), py::arg("dims"), py::arg("seed") = 0, py::arg("randomization") = "none",
          py::arg("start") = 0,
          "Points start .. start + n - 1 of the Halton sequence (dimension k: the radical inverse in the k-th\n"
          "prime base) as an (n, dims) float64 array in [0, 1). randomization: 'none' (plain; seed unused),\n"
          "'cp' (Cranley-Patterson shifts), 'perm' (random digit permutations) or 'owen' (Owen scrambling),\n"
          "each drawn from `seed`.");
}

}  // namespace glint::python
