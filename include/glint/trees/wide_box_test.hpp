// glint/trees/wide_box_test.hpp: the slab test of one wide node's N child boxes against
// one ray, per instruction set (core/isa.hpp): AVX2 for N = 8, SSE for N = 4, a portable
// loop otherwise and on request; all three compute the same floats. The AVX2 test is
// compiled for AVX2 whatever the flags, so it may only run inside a function compiled for
// AVX2 too (WideBvh's dispatch).
//
// The test is conservative (Ize, "Robust BVH Ray Traversal", JCGT 2013): the exit distance
// is enlarged by 1 + 2 gamma_3 (the bound on the rounding of (plane - o) / d), so a box the
// ray meets is never rejected by rounding; for an interval starting below 0 (tmin < 0),
// whose boxes behind the origin have negative distances, both ends are moved outward
// instead (wide_lower, wide_upper); a NaN slab distance (a ray lying in a box face)
// constrains nothing. Rays with NaN or infinite coordinates, a zero direction or an
// interval that is not ordered (tmin <= tmax, false for a NaN) hit nothing (wide_ray_valid).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include <glint/core/isa.hpp>
#include <glint/core/math.hpp>
#include <glint/core/ray.hpp>
#include <glint/trees/wide_node.hpp>

#if GLINT_X86
#include <immintrin.h>
#endif

namespace glint {

namespace detail {

/// 1 + 2 gamma_3 rounded up, gamma_n = n u / (1 - n u), u = 2^-24 (Ize 2013; pbrt-v3 3.9).
inline constexpr float wide_exit_scale = 1.0f + 2.0f * (3.0f * 0x1p-24f / (1.0f - 3.0f * 0x1p-24f)) + 0x1p-23f;
/// 1 - (wide_exit_scale - 1), exactly (Sterbenz).
inline constexpr float wide_entry_scale = 2.0f - wide_exit_scale;

/// Ize's enlarged exit distance t1 * wide_exit_scale holds for t1 >= 0, which every box the
/// ray may enter has when the interval starts at tmin >= 0 (rounding keeps a distance's
/// sign). An interval reaching below 0 (tmin < 0) can enter boxes behind the origin, where
/// that product would shrink a negative exit: a computed distance c (three roundings, within
/// gamma_3 |c| of the true one) is moved away from the box on both ends instead, the entry
/// down to c * (c < 0 ? wide_exit_scale : wide_entry_scale) and the exit up to c * (c < 0 ?
/// wide_entry_scale : wide_exit_scale), each beyond the true distance by more than the
/// product's own rounding.
[[gnu::always_inline]] inline float wide_lower(float c) { return c * (c < 0.0f ? wide_exit_scale : wide_entry_scale); }
[[gnu::always_inline]] inline float wide_upper(float c) { return c * (c < 0.0f ? wide_entry_scale : wide_exit_scale); }
/// An exit distance (or the interval's end) as the test enlarges it.
template <bool Signed>
[[gnu::always_inline]] inline float wide_exit_bound(float t) {
    if constexpr (Signed) return wide_upper(t);
    else return t * wide_exit_scale;
}

/// The per-ray data of the slab test, and the test of one node's N boxes: a bit mask of the
/// children entered within (tmin, tmax), their entry distances in tn.
template <int N, Isa I, bool Signed = false>
struct WideBoxTest {
    float o[3], inv[3];
    int near[3], far[3];  // bounds rows of the entry and exit planes per axis

    [[gnu::always_inline]] explicit WideBoxTest(const Ray<float>& r) {
        for (int a = 0; a < 3; ++a) {
            o[a] = r.origin[a];
            inv[a] = 1.0f / r.direction[a];
            const int neg = std::signbit(r.direction[a]) ? 1 : 0;
            near[a] = 2 * a + neg;
            far[a] = 2 * a + 1 - neg;
        }
    }
    unsigned test(const WideBvhNode<N>& n, float tmin, float tmax, float* tn) const {
        unsigned mask = 0;
        for (int i = 0; i < N; ++i) {
            float t0 = tmin, t1 = tmax;
            for (int a = 0; a < 3; ++a) {
                const float tl = (n.bounds[near[a]][i] - o[a]) * inv[a];
                const float th = (n.bounds[far[a]][i] - o[a]) * inv[a];
                t0 = tl > t0 ? tl : t0;  // max, keeping t0 for a NaN slab (as maxps)
                t1 = th < t1 ? th : t1;
            }
            if constexpr (Signed) t0 = wide_lower(t0);
            tn[i] = t0;
            mask |= unsigned(t0 <= wide_exit_bound<Signed>(t1)) << i;
        }
        return mask;
    }
    /// Quantized nodes: the planes decoded (the AVX2 path computes the same floats).
    unsigned test(const WideBvhQNode<N>& n, float tmin, float tmax, float* tn) const {
        return test(wide_decode(n), tmin, tmax, tn);
    }
};

#if GLINT_X86
/// 8-wide nodes with AVX2: the same operations as the portable loop, in the same order.
template <bool Signed>
struct WideBoxTest<8, Isa::avx2, Signed> {
    __m256 o[3], inv[3];
    std::size_t near[3], far[3];  // byte offsets of the rows in a node

    GLINT_KERNEL_AVX2_INLINE explicit WideBoxTest(const Ray<float>& r) {
        // 1 / d for the three axes with one division (the same correctly rounded quotients).
        alignas(16) float q[4];
        _mm_store_ps(q, _mm_div_ps(_mm_set1_ps(1.0f), _mm_setr_ps(r.direction.x, r.direction.y, r.direction.z, 1.0f)));
        for (int a = 0; a < 3; ++a) {
            o[a] = _mm256_set1_ps(r.origin[a]);
            inv[a] = _mm256_set1_ps(q[a]);
            const std::size_t neg = std::signbit(r.direction[a]) ? 1 : 0;
            near[a] = (2 * std::size_t(a) + neg) * sizeof(__m256);
            far[a] = (2 * std::size_t(a) + 1 - neg) * sizeof(__m256);
        }
    }
    GLINT_KERNEL_AVX2_INLINE unsigned test(const WideBvhNode<8>& n, float tmin, float tmax, float* tn) const {
        __m256 t0 = _mm256_set1_ps(tmin), t1 = _mm256_set1_ps(tmax);
        const char* rows = reinterpret_cast<const char*>(n.bounds);
        for (int a = 0; a < 3; ++a) {
            const __m256 tl = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(reinterpret_cast<const float*>(rows + near[a])), o[a]), inv[a]);
            const __m256 th = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(reinterpret_cast<const float*>(rows + far[a])), o[a]), inv[a]);
            t0 = _mm256_max_ps(tl, t0);  // tl > t0 ? tl : t0
            t1 = _mm256_min_ps(th, t1);  // th < t1 ? th : t1
        }
        return finish(t0, t1, tn);
    }
    GLINT_KERNEL_AVX2_INLINE unsigned test(const WideBvhQNode<8>& n, float tmin, float tmax, float* tn) const {
        __m256 t0 = _mm256_set1_ps(tmin), t1 = _mm256_set1_ps(tmax);
        const char* rows = reinterpret_cast<const char*>(n.q);
        for (int a = 0; a < 3; ++a) {
            const __m256 org = _mm256_broadcast_ss(&n.origin[a]), s = _mm256_set1_ps(wide_scale(n.exp[a]));
            const __m256 tl = _mm256_mul_ps(_mm256_sub_ps(plane(rows, near[a], org, s), o[a]), inv[a]);
            const __m256 th = _mm256_mul_ps(_mm256_sub_ps(plane(rows, far[a], org, s), o[a]), inv[a]);
            t0 = _mm256_max_ps(tl, t0);
            t1 = _mm256_min_ps(th, t1);
        }
        const unsigned used = (1u << n.count) - 1u;
        return finish(t0, t1, tn) & used;
    }

private:
    /// A quantized node's 8 planes of one row (its byte offset is the float row's / 4), decoded.
    GLINT_KERNEL_AVX2_INLINE static __m256 plane(const char* rows, std::size_t row_offset, __m256 origin, __m256 scale) {
        const __m128i q = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(rows + row_offset / 4));
        return _mm256_add_ps(origin, _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(q)), scale));
    }
    /// Entry distances to tn, and the mask of children entered (the portable test's ends).
    GLINT_KERNEL_AVX2_INLINE unsigned finish(__m256 t0, __m256 t1, float* tn) const {
        const __m256 up = _mm256_set1_ps(wide_exit_scale), down = _mm256_set1_ps(wide_entry_scale);
        if constexpr (Signed) {  // blendv picks its second operand where the sign bit is set
            t0 = _mm256_mul_ps(t0, _mm256_blendv_ps(down, up, t0));
            t1 = _mm256_mul_ps(t1, _mm256_blendv_ps(up, down, t1));
        } else {
            t1 = _mm256_mul_ps(t1, up);
        }
        _mm256_storeu_ps(tn, t0);
        return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ)));
    }
};

/// 4-wide nodes with SSE.
template <bool Signed>
struct WideBoxTest<4, Isa::sse2, Signed> {
    __m128 o[3], inv[3];
    int near[3], far[3];

    [[gnu::always_inline]] explicit WideBoxTest(const Ray<float>& r) {
        const WideBoxTest<4, Isa::portable> s(r);
        for (int a = 0; a < 3; ++a) {
            o[a] = _mm_set1_ps(s.o[a]);
            inv[a] = _mm_set1_ps(s.inv[a]);
            near[a] = s.near[a];
            far[a] = s.far[a];
        }
    }
    [[gnu::always_inline]] unsigned test(const WideBvhNode<4>& n, float tmin, float tmax, float* tn) const {
        __m128 t0 = _mm_set1_ps(tmin), t1 = _mm_set1_ps(tmax);
        for (int a = 0; a < 3; ++a) {
            const __m128 tl = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n.bounds[near[a]]), o[a]), inv[a]);
            const __m128 th = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n.bounds[far[a]]), o[a]), inv[a]);
            t0 = _mm_max_ps(tl, t0);
            t1 = _mm_min_ps(th, t1);
        }
        const __m128 up = _mm_set1_ps(wide_exit_scale), down = _mm_set1_ps(wide_entry_scale);
        if constexpr (Signed) {  // -0 takes the scale of +0, as in the portable test (either keeps -0)
            const __m128 n0 = _mm_cmplt_ps(t0, _mm_setzero_ps()), n1 = _mm_cmplt_ps(t1, _mm_setzero_ps());
            t0 = _mm_mul_ps(t0, _mm_or_ps(_mm_and_ps(n0, up), _mm_andnot_ps(n0, down)));
            t1 = _mm_mul_ps(t1, _mm_or_ps(_mm_and_ps(n1, down), _mm_andnot_ps(n1, up)));
        } else {
            t1 = _mm_mul_ps(t1, up);
        }
        _mm_storeu_ps(tn, t0);
        return unsigned(_mm_movemask_ps(_mm_cmple_ps(t0, t1)));
    }
    unsigned test(const WideBvhQNode<4>& n, float tmin, float tmax, float* tn) const {
        return test(wide_decode(n), tmin, tmax, tn);
    }
};

/// 4-wide nodes where AVX2 runs: the SSE test (compiled with VEX encodings there).
template <bool Signed>
struct WideBoxTest<4, Isa::avx2, Signed> : WideBoxTest<4, Isa::sse2, Signed> {
    using WideBoxTest<4, Isa::sse2, Signed>::WideBoxTest;
};
#endif

/// Whether traversal can give the ray any hit (see the file comment): x * 0 is 0 for a
/// finite x and NaN otherwise, so one comparison checks all six coordinates.
[[gnu::always_inline]] inline bool wide_ray_valid(const Ray<float>& r) {
    const Vec3f& o = r.origin;
    const Vec3f& d = r.direction;
    const float z = (o.x * 0.0f + o.y * 0.0f) + (o.z * 0.0f + d.x * 0.0f) + (d.y * 0.0f + d.z * 0.0f);
    return (z == 0.0f) & ((d.x != 0.0f) | (d.y != 0.0f) | (d.z != 0.0f)) & (r.tmin <= r.tmax);
}

}  // namespace detail

}  // namespace glint
