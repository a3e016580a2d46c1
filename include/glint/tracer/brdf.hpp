// glint/tracer/brdf.hpp: glint's one material model. A scene Material (tracer/scene.hpp) is
// either a multi-lobe BRDF in a local shading frame (z = normal, wo = direction towards the
// viewer), SurfaceBrdf, for glint::scatter (sampling/roulette.hpp) and light sampling, or a
// specular surface (mirror, dielectric) with one scattering direction, specular_scatter. The
// path tracer, the VPL method (shooting and gathering) and the roulette tests all use it.
//
// Lobe 0 is Lambertian (kd / pi, cosine sampled). Lobe 1, for glossy materials, is the
// energy-normalized Phong lobe ks (n + 2) / (2 pi) cos^n(alpha) about the mirror direction
// r = (-wo.x, -wo.y, wo.z), sampled with density (n + 1) / (2 pi) cos^n(alpha) about r; a
// sample below the horizon has w = 0 (its weight is zero, which is what makes the Phong
// density unable to cover the diffuse lobe: the W estimator of Szécsi 2009, §2.1 is biased
// here, DIS and MIS are not). Lobe albedos: kd, and ks (the Phong lobe's albedo at normal
// incidence; the roulette only needs a positive selection weight). Seen from the normal
// (wo = z) the Phong lobe is about the normal and covers the whole hemisphere, so there DIS,
// W and MIS are all unbiased (tests/test_sampling.cpp checks them on it).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include <glint/core/math.hpp>
#include <glint/core/optics.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/sampling/roulette.hpp>
#include <glint/sampling/warps.hpp>
#include <glint/tracer/scene.hpp>

namespace glint {

template <Scalar T>
/// The BRDF of a Lambertian or glossy Material seen from one direction, in the local shading
/// frame (z = normal): a MultiLobeBrdf of one lobe (Lambertian) or two (plus Phong), as the
/// header comment defines them. Cheap to build per shading point; specular materials use
/// specular_scatter instead.
class SurfaceBrdf {
public:
    /// The BRDF of `m` (its kind must be lambertian or glossy) for the unit direction `wo_local`
    /// towards the viewer, in the shading frame (wo_local.z > 0 on the visible side).
    [[gnu::always_inline]] SurfaceBrdf(const Material<T>& m, const Vec3<T>& wo_local)
        : kd_(m.kd), ks_(m.ks), n_(m.exponent), wo_(wo_local),
          lobes_(m.kind == MaterialKind::glossy ? 2 : 1) {
        r_ = Vec3<T>(-wo_.x, -wo_.y, wo_.z);
        if (lobes_ > 1) orthonormal_basis(r_, rb1_, rb2_);  // only the Phong lobe samples about r
    }

    /// Number of lobes: 2 for a glossy material (Lambertian + Phong), else 1.
    std::size_t lobe_count() const { return lobes_; }
    /// Selection weight of lobe i for the roulette: kd for lobe 0, ks for lobe 1.
    Rgb<T> albedo(std::size_t i) const { return i == 0 ? kd_ : ks_; }

    /// A local direction drawn from lobe i's density pdf(i, ·) with the uniform pair u in
    /// [0, 1)^2; a Phong sample may lie below the horizon (then eval gives 0).
    Vec3<T> sample(std::size_t i, const Vec2<T>& u) const {
        if (i == 0) return square_to_cosine_hemisphere(u);
        const Vec3<T> l = square_to_cosine_power_hemisphere(u, n_);
        return rb1_ * l.x + rb2_ * l.y + r_ * l.z;
    }
    /// Solid-angle density (1/sr) with which sample(i, ·) draws the unit local direction wi;
    /// 0 outside the lobe's hemisphere.
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
        const T p0 = lobe0_probability();
        return p0 < T(1) ? p0 * pdf(0, wi) + (T(1) - p0) * pdf(1, wi) : pdf(0, wi);
    }
    /// True for a Lambertian material (no Phong lobe).
    bool diffuse_only() const { return lobes_ == 1; }
    /// Diffuse reflectance of the Lambertian lobe (f = kd / pi).
    const Rgb<T>& kd() const { return kd_; }
    /// The Phong lobe's ks, exponent and mirror direction (local): what a bound on f needs.
    const Rgb<T>& ks() const { return ks_; }
    /// Phong exponent n of lobe 1 (meaningless when diffuse_only()).
    T exponent() const { return n_; }
    /// Unit mirror direction of wo about the normal in the local frame, the Phong lobe's axis.
    const Vec3<T>& mirror() const { return r_; }

private:
    Rgb<T> kd_, ks_;
    T n_;
    Vec3<T> wo_, r_, rb1_{}, rb2_{};
    std::size_t lobes_;
};

static_assert(MultiLobeBrdf<SurfaceBrdf<float>, float, 3>);

/// The albedo a walk carries through a specular Material: ks for a mirror, 1 for a dielectric
/// (what it does not reflect it transmits).
template <Scalar T>
Rgb<T> specular_albedo(const Material<T>& m) {
    return m.kind == MaterialKind::mirror ? m.ks : Rgb<T>(T(1));
}

/// The one direction a specular Material (precondition: m.specular()) sends the ray direction
/// d in, at a surface of geometric normal ng (either side): a mirror reflects; a dielectric
/// reflects with the Fresnel reflectance (core/optics.hpp; ior relative to the side ng points
/// away from) and refracts otherwise, chosen by u in [0, 1).
template <Scalar T>
Vec3<T> specular_direction(const Material<T>& m, const Vec3<T>& d, const Vec3<T>& ng, T u) {
    const Vec3<T> dn = safe_normalize(d);
    const bool inside = glm::dot(dn, ng) > T(0);
    const Vec3<T> n = inside ? -ng : ng;  // facing the incoming ray
    const T cos_i = -glm::dot(dn, n);
    const Vec3<T> reflected = dn + n * (T(2) * cos_i);
    if (m.kind == MaterialKind::mirror) return reflected;
    const T eta = inside ? m.ior : T(1) / m.ior;
    Vec3<T> refracted;
    const T cos_t = refract(dn, n, eta, refracted);
    if (cos_t < T(0) || u < fresnel_dielectric(cos_i, cos_t, eta)) return reflected;
    return refracted;
}

}  // namespace glint
