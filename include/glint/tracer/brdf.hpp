// glint/tracer/brdf.hpp: the scene materials as multi-lobe BRDFs in a local shading frame
// (z = normal, wo = direction towards the viewer), for glint::scatter (sampling/roulette.hpp)
// and for light sampling.
//
// Lobe 0 is Lambertian (kd / pi, cosine sampled). Lobe 1, for glossy materials, is the
// energy-normalized Phong lobe ks (n + 2) / (2 pi) cos^n(alpha) about the mirror direction
// r = (-wo.x, -wo.y, wo.z), sampled with density (n + 1) / (2 pi) cos^n(alpha) about r; a
// sample below the horizon has w = 0 (its weight is zero, which is what makes the Phong
// density unable to cover the diffuse lobe: the W estimator of 000 section 2.1 is biased
// here, DIS and MIS are not). Lobe albedos: kd, and ks (the Phong lobe's albedo at normal
// incidence; the roulette only needs a positive selection weight).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

template <Scalar T>
class SurfaceBrdf {
public:
    SurfaceBrdf(const Material<T>& m, const Vec3<T>& wo_local)
        : kd_(m.kd), ks_(m.ks), n_(m.exponent), wo_(wo_local),
          lobes_(m.kind == MaterialKind::glossy ? 2 : 1) {
        r_ = Vec3<T>(-wo_.x, -wo_.y, wo_.z);
        if (lobes_ > 1) orthonormal_basis(r_, rb1_, rb2_);  // only the Phong lobe samples about r
    }

    std::size_t lobe_count() const { return lobes_; }
    Rgb<T> albedo(std::size_t i) const { return i == 0 ? kd_ : ks_; }

    Vec3<T> sample(std::size_t i, const Vec2<T>& u) const {
        if (i == 0) return square_to_cosine_hemisphere(u);
        const Vec3<T> l = square_to_cosine_power_hemisphere(u, n_);
        return rb1_ * l.x + rb2_ * l.y + r_ * l.z;
    }
    T pdf(std::size_t i, const Vec3<T>& wi) const {
        if (i == 0) return wi.z > T(0) ? wi.z / pi<T> : T(0);
        const T c = glm::dot(wi, r_);
        return c > T(0) ? (n_ + T(1)) / (T(2) * pi<T>) * std::pow(c, n_) : T(0);
    }
    /// w_i(wi) = f_i(wi) cos(theta_i).
    Rgb<T> eval(std::size_t i, const Vec3<T>& wi) const {
        if (wi.z <= T(0)) return Rgb<T>(T(0));
        if (i == 0) return kd_ * (wi.z / pi<T>);
        const T c = glm::dot(wi, r_);
        if (c <= T(0)) return Rgb<T>(T(0));
        return ks_ * ((n_ + T(2)) / (T(2) * pi<T>) * std::pow(c, n_) * wi.z);
    }
    /// f(wi) = sum of the lobes' BRDFs (without the cosine).
    Rgb<T> f(const Vec3<T>& wi) const {
        if (wi.z <= T(0)) return Rgb<T>(T(0));
        Rgb<T> out = kd_ / pi<T>;
        if (lobes_ > 1) {
            const T c = glm::dot(wi, r_);
            if (c > T(0)) out += ks_ * ((n_ + T(2)) / (T(2) * pi<T>) * std::pow(c, n_));
        }
        return out;
    }
    /// Probability of choosing lobe 0 when sampling a direction without a roulette: in
    /// proportion to the luminance of the lobes' albedos (1 with one lobe or none reflecting).
    T lobe0_probability() const {
        if (lobes_ == 1) return T(1);
        const T a0 = kd_.luminance(), a1 = ks_.luminance();
        return a0 + a1 > T(0) ? a0 / (a0 + a1) : T(1);
    }
    /// A direction by the lobe choice of lobe0_probability (u.x picks the lobe and is reused).
    Vec3<T> sample_by_albedo(Vec2<T> u) const {
        const T p0 = lobe0_probability();
        if (u.x < p0) {
            u.x = std::min(u.x / p0, T(1) - std::numeric_limits<T>::epsilon());
            return sample(0, u);
        }
        u.x = std::min((u.x - p0) / (T(1) - p0), T(1) - std::numeric_limits<T>::epsilon());
        return sample(1, u);
    }
    /// Density of sample_by_albedo, for multiple importance sampling with light sampling.
    T sampling_pdf(const Vec3<T>& wi) const {
        if (lobes_ == 1) return pdf(0, wi);
        const T a0 = kd_.luminance(), a1 = ks_.luminance();
        if (!(a0 + a1 > T(0))) return T(0);
        const T p0 = lobe0_probability();
        return p0 * pdf(0, wi) + (T(1) - p0) * pdf(1, wi);
    }
    bool diffuse_only() const { return lobes_ == 1; }
    const Rgb<T>& kd() const { return kd_; }

private:
    Rgb<T> kd_, ks_;
    T n_;
    Vec3<T> wo_, r_, rb1_{}, rb2_{};
    std::size_t lobes_;
};

static_assert(MultiLobeBrdf<SurfaceBrdf<float>, float, 3>);

}  // namespace glint
