// glint/lights/importance_pair.hpp: the importance (CompactLightBounds::importance, the light
// tree's bound of Conty Estevez and Kulla 2018, §4) of two clusters at one shading point, the
// pair a light tree's descent compares at every level. For float on x86 (SSE2) the two are
// evaluated in the lanes of one SSE register: the same operations, lane by lane, with the
// scalar version's branches as selections, so that a level costs about one evaluation's
// instructions; elsewhere, two scalar evaluations. Results agree with the scalar ones up to
// rounding (the scalar code may fuse multiply-adds); what matters for a tree is that its pick
// and its probability both go through this function.
#pragma once

#include <array>

#include <glint/lights/light_bounds.hpp>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace glint {

/// The importance of clusters a and b at x with normal n (0: no receiver cosine).
template <Scalar T>
std::array<T, 2> importance_pair(const CompactLightBounds<T>& a, const CompactLightBounds<T>& b, const Vec3<T>& x,
                                 const Vec3<T>& n) {
    return {a.importance(x, n), b.importance(x, n)};
}

#if defined(__SSE2__)
namespace detail {

struct Sse {
    __m128 v;
    friend Sse operator+(Sse p, Sse q) { return {_mm_add_ps(p.v, q.v)}; }
    friend Sse operator-(Sse p, Sse q) { return {_mm_sub_ps(p.v, q.v)}; }
    friend Sse operator*(Sse p, Sse q) { return {_mm_mul_ps(p.v, q.v)}; }
    friend Sse operator/(Sse p, Sse q) { return {_mm_div_ps(p.v, q.v)}; }
};
inline Sse lanes(float p, float q) { return {_mm_setr_ps(p, q, p, q)}; }
inline Sse splat(float s) { return {_mm_set1_ps(s)}; }
inline Sse root(Sse p) { return {_mm_sqrt_ps(_mm_max_ps(p.v, _mm_setzero_ps()))}; }
inline Sse max0(Sse p) { return {_mm_max_ps(p.v, _mm_setzero_ps())}; }
/// m ? p : q, lane by lane (m: a comparison's all-ones or all-zeros lanes).
inline Sse select(__m128 m, Sse p, Sse q) { return {_mm_or_ps(_mm_and_ps(m, p.v), _mm_andnot_ps(m, q.v))}; }
/// cos(max(0, alpha - beta)) and sin(max(0, alpha - beta)) (detail::cos_sub_clamped, sin_sub_clamped).
inline Sse cos_sub(Sse sa, Sse ca, Sse sb, Sse cb) { return select(_mm_cmpgt_ps(ca.v, cb.v), splat(1), ca * cb + sa * sb); }
inline Sse sin_sub(Sse sa, Sse ca, Sse sb, Sse cb) { return select(_mm_cmpgt_ps(ca.v, cb.v), splat(0), sa * cb - ca * sb); }

}  // namespace detail

/// Both clusters in SSE lanes (lanes 2 and 3 repeat them); each step is the scalar one's.
inline std::array<float, 2> importance_pair(const CompactLightBounds<float>& a, const CompactLightBounds<float>& b,
                                            const Vec3<float>& x, const Vec3<float>& n) {
    using detail::lanes, detail::splat, detail::root, detail::Sse;
    const Sse dx = splat(x.x) - lanes(a.c.x, b.c.x), dy = splat(x.y) - lanes(a.c.y, b.c.y);
    const Sse dz = splat(x.z) - lanes(a.c.z, b.c.z);
    const Sse d2 = dx * dx + dy * dy + dz * dz, r2 = lanes(a.r2, b.r2), phi = lanes(a.phi, b.phi);
    const Sse dw = lanes(a.w.x, b.w.x) * dx + lanes(a.w.y, b.w.y) * dy + lanes(a.w.z, b.w.z) * dz;
    const Sse dn = splat(0) - (dx * splat(n.x) + dy * splat(n.y) + dz * splat(n.z));
    const Sse inv_d = splat(1) / root(d2);
    const Sse sin_b = lanes(a.r, b.r) * inv_d, cos_b = root(d2 - r2) * inv_d;
    const Sse cos_w = dw * inv_d, sin_w = root(d2 - dw * dw) * inv_d;
    const Sse sin_o = lanes(a.sin_theta_o, b.sin_theta_o), cos_o = lanes(a.cos_theta_o, b.cos_theta_o);
    const Sse cos_x = detail::cos_sub(sin_w, cos_w, sin_o, cos_o), sin_x = detail::sin_sub(sin_w, cos_w, sin_o, cos_o);
    const Sse cos_p = detail::cos_sub(sin_x, cos_x, sin_b, cos_b), cos_e = lanes(a.cos_theta_e, b.cos_theta_e);
    Sse imp = phi * detail::max0(cos_p) * (inv_d * inv_d);
    if (glm::dot(n, n) > 0.0f) imp = imp * detail::max0(detail::cos_sub(root(d2 - dn * dn) * inv_d, dn * inv_d, sin_b, cos_b));
    imp = detail::select(_mm_cmpgt_ps(cos_p.v, cos_e.v), imp, splat(0));
    // Inside the sphere: phi / r^2 where any direction is lit; no power: 0.
    const Sse inside = detail::select(_mm_cmplt_ps(cos_e.v, splat(1).v), phi / r2, splat(0));
    imp = detail::select(_mm_cmpgt_ps(d2.v, r2.v), imp, inside);
    imp = detail::select(_mm_cmpgt_ps(phi.v, splat(0).v), imp, splat(0));
    alignas(16) float out[4];
    _mm_store_ps(out, imp.v);
    return {out[0], out[1]};
}
#endif

}  // namespace glint
