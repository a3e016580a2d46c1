// tests/support/image_error.hpp: the relative RMSE of one image against another, the error
// measure of the VPL and occluder comparisons (a fixture of tests, benchmarks and examples,
// not part of the library).
#pragma once

#include <cmath>
#include <span>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// Relative RMSE of `img` against `ref` over all pixels and channels:
/// sqrt(sum (img - ref)^2 / sum ref^2).
template <Scalar T>
double relative_rmse(std::span<const Rgb<T>> img, std::span<const Rgb<T>> ref) {
    if (img.size() != ref.size()) throw Error("glint::relative_rmse: images differ in size");
    double num = 0, den = 0;
    for (std::size_t i = 0; i < img.size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            const double e = double(img[i][c]) - double(ref[i][c]);
            num += e * e;
            den += double(ref[i][c]) * double(ref[i][c]);
        }
    return den > 0 ? std::sqrt(num / den) : 0.0;
}

}  // namespace glint
