// glint/photons/hemiplane.hpp: final gathering onto the front plane of an enlarged hemicube
// (Larsen 2004, ch. 11; the hemicube of Cohen and Greenberg 1985 with only its front face,
// enlarged).
//
// The plane z = 1 above a point (normal along z) is cut into R x R square pixels over
// [-a, a]^2; a pixel at (x, y) of area dA covers the cosine-weighted share
//   F_h(x, y) = dA / (pi (x^2 + y^2 + 1)^2)                                   (Larsen eq. 11.2)
// of the hemisphere. The shares sum to the plane's form factor, in closed form
//   F(a) = (4 / pi) s atan(s),   s = a / sqrt(1 + a^2)
// (a differential area to a parallel square centred above it): 0.5541 for the hemicube's own
// front face (a = 1) and 0.8310 for the face enlarged to twice its side (a = 2, Larsen's
// choice; he quotes about 86 %). The irradiance gathered from radiances L_p seen through the
// pixels' centres is
//   E = pi sum_p L_p F_h(p) / sum_p F_h(p),
// i.e. eq. 11.3 times pi, divided by the covered fraction: the directions outside the plane
// (grazing ones) are assumed to bring the plane's mean radiance. Under uniform radiance L
// this is pi L exactly; light that arrives only within the plane is overestimated by
// 1 / sum_p F_h(p) (1.20 at a = 2), light from outside it is missed: the method's bias.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/tracer/light_walk.hpp>

namespace glint {

/// Cosine-weighted share of the hemisphere seen through the square [-a, a]^2 at distance 1.
template <Scalar T>
T hemiplane_fraction(T a) {
    const T s = a / std::sqrt(T(1) + a * a);
    return T(4) / pi<T> * s * std::atan(s);
}

/// The enlarged hemicube front plane of Larsen 2004, ch. 11: fixed gather directions and their
/// shares F_h, built once; gather() is const.
template <Scalar T>
class HemiPlane {
public:
    /// resolution R pixels along a side, extent a (half side of the plane at distance 1).
    HemiPlane(int resolution, T extent) {
        if (resolution < 1 || resolution > 4096)
            throw Error("glint::HemiPlane: resolution must be in [1, 4096] (got " + std::to_string(resolution) + ")");
        if (!(extent > T(0)) || !std::isfinite(extent))
            throw Error("glint::HemiPlane: extent must be positive and finite (got " + std::to_string(extent) + ")");
        const T h = T(2) * extent / T(resolution);
        for (int j = 0; j < resolution; ++j)
            for (int i = 0; i < resolution; ++i) {
                const T x = -extent + (T(i) + T(0.5)) * h, y = -extent + (T(j) + T(0.5)) * h;
                const T q = x * x + y * y + T(1);
                directions_.push_back(glm::normalize(Vec3<T>(x, y, T(1))));
                weights_.push_back(h * h / (pi<T> * q * q));
                fraction_ += weights_.back();
            }
    }

    /// Sum of the pixels' shares F_h: the covered fraction of the cosine-weighted hemisphere.
    T fraction() const { return fraction_; }
    /// Unit directions through the pixels' centres, row by row; local, z the normal.
    const std::vector<Vec3<T>>& directions() const { return directions_; }
    /// The pixels' shares F_h (eq. 11.2), aligned with directions().
    const std::vector<T>& weights() const { return weights_; }

    /// E = pi sum L F_h / fraction at x with normal n; radiance(const Ray<T>&, const StoreHit<T>&)
    /// gives the radiance towards x at a hit; misses bring nothing.
    template <class Queries, class Radiance>
    Rgb<T> gather(Queries& queries, const Vec3<T>& x, const Vec3<T>& n, const Radiance& radiance) const {
        const Frame<T> frame = Frame<T>::from_normal(n);
        Rgb<T> sum(T(0));
        for (std::size_t p = 0; p < directions_.size(); ++p) {
            const Ray<T> ray = detail::light_spawn(x, n, frame.to_world(directions_[p]));
            StoreHit<T> hit;
            if (queries.closest_hit(ray, hit)) sum += radiance(ray, hit) * weights_[p];
        }
        return sum * (pi<T> / fraction_);
    }

private:
    std::vector<Vec3<T>> directions_;
    std::vector<T> weights_;
    T fraction_ = T(0);
};

}  // namespace glint
