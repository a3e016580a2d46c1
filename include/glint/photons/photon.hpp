// glint/photons/photon.hpp: the compact photon of a photon map, as Jensen 2001, ch. 5 lays it
// out (Larsen 2004, §8.2 used 40 bytes a photon): position as three floats, power in Ward's shared-exponent
// RGBE form (4 bytes), the incoming direction and the surface normal on the side the photon
// arrived from as two bytes of spherical angles each: 20 bytes. (Jensen's photon keeps the
// kd-tree's split axis in its last two bytes; glint's tree, photons/photon_map.hpp, keeps
// the axes beside the positions, so those bytes hold the normal, which the irradiance
// estimate and its precomputation, Christensen 1999, use to reject photons of other surfaces.)
//
// RGBE here rounds each band's mantissa to nearest (Ward's original truncates and decodes
// at the bin's centre): a band within 2^-9 of the largest band's value, relative, after a
// round trip; bands below 2^-8 of the largest are flushed towards zero. The direction is
// and the normal are quantized to 256 steps of theta in [0, pi] and of phi in [0, 2 pi):
// within 0.02 rad.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>

namespace glint {

/// Ward's RGBE: three 8-bit mantissas sharing one exponent, rounded to nearest.
inline std::array<std::uint8_t, 4> encode_rgbe(float r, float g, float b) {
    const float v = std::max({r, g, b});
    if (!(v > 1e-32f) || !std::isfinite(v)) return {0, 0, 0, 0};
    int e = 0;
    std::frexp(v, &e);  // v = m 2^e, m in [0.5, 1)
    float scale = std::ldexp(1.0f, 8 - e);
    if (std::lround(v * scale) > 255) scale = std::ldexp(1.0f, 8 - ++e);  // rounding reached 256
    auto q = [&](float c) { return std::uint8_t(std::clamp(std::lround(std::max(c, 0.0f) * scale), 0L, 255L)); };
    return {q(r), q(g), q(b), std::uint8_t(std::clamp(e + 128, 0, 255))};
}

/// The colour an RGBE value stands for; (0, 0, 0) for exponent byte 0.
inline Rgb<float> decode_rgbe(const std::array<std::uint8_t, 4>& c) {
    if (c[3] == 0) return Rgb<float>(0.0f);
    const float f = std::ldexp(1.0f, int(c[3]) - (128 + 8));
    return Rgb<float>(float(c[0]) * f, float(c[1]) * f, float(c[2]) * f);
}

namespace detail {

/// A unit vector as two bytes of spherical angles, and back (the bins' centres).
inline std::array<std::uint8_t, 2> encode_direction(const Vec3<float>& d) {
    const float len = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    const float t = std::acos(len > 0.0f ? std::clamp(d.z / len, -1.0f, 1.0f) : 1.0f);
    float f = std::atan2(d.y, d.x);
    if (f < 0.0f) f += 2.0f * pi<float>;
    return {std::uint8_t(std::min(255, int(t * (256.0f / pi<float>)))),
            std::uint8_t(std::min(255, int(f * (256.0f / (2.0f * pi<float>)))))};
}
inline Vec3<float> decode_direction(const std::array<std::uint8_t, 2>& c) {
    const float t = (float(c[0]) + 0.5f) * (pi<float> / 256.0f);
    const float f = (float(c[1]) + 0.5f) * (2.0f * pi<float> / 256.0f);
    return Vec3<float>(std::sin(t) * std::cos(f), std::sin(t) * std::sin(f), std::cos(t));
}

}  // namespace detail

/// One stored photon (Jensen 2001, ch. 5): 20 bytes.
struct Photon {
    Vec3<float> position{0.0f};                    ///< World-space point where it was stored.
    std::array<std::uint8_t, 4> rgbe{0, 0, 0, 0};  ///< Power, Ward's RGBE.
    std::array<std::uint8_t, 2> incoming{0, 0};    ///< Direction it travelled in, quantized.
    std::array<std::uint8_t, 2> surface{0, 0};     ///< Normal on the side it arrived from, quantized.

    Photon() = default;
    /// A photon at p of power `power` (W per band) that travelled along `direction` onto a
    /// surface of normal `normal`; both are quantized and need not be unit length.
    Photon(const Vec3<float>& p, const Rgb<float>& power, const Vec3<float>& direction, const Vec3<float>& normal)
        : position(p), rgbe(encode_rgbe(power[0], power[1], power[2])),
          incoming(detail::encode_direction(direction)), surface(detail::encode_direction(normal)) {}

    /// The photon's power (W per band), as RGBE decodes it.
    Rgb<float> power() const { return decode_rgbe(rgbe); }
    /// Stores power p (W per band), rounded to RGBE; negative bands become 0.
    void set_power(const Rgb<float>& p) { rgbe = encode_rgbe(p[0], p[1], p[2]); }
    /// The unit direction the photon travelled in when it arrived (towards the surface).
    Vec3<float> direction() const { return detail::decode_direction(incoming); }
    /// Stores the arrival direction d, quantized to 256 x 256 spherical-angle bins.
    void set_direction(const Vec3<float>& d) { incoming = detail::encode_direction(d); }
    /// The unit surface normal on the side the photon arrived from.
    Vec3<float> normal() const { return detail::decode_direction(surface); }
};

static_assert(sizeof(Photon) == 20, "glint::Photon is Jensen's 20-byte photon");

}  // namespace glint
