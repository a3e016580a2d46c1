// glint/intersection/moller_trumbore.hpp: the Moller-Trumbore ray-triangle test.
//
// Moller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection" (JGT 1997): solve
// o + t d = (1 - u - v) v0 + u v1 + v v2 by Cramer's rule with two cross products and no
// precomputed plane. 000 section 4.1.1 compares the IVM test against it as
// "the fastest known ... working without precomputed values". Our record keeps v0 and the
// two edges e1 = v1 - v0, e2 = v2 - v0 (9 scalars, the same footprint as the IVM), which is
// how it is usually deployed and the strongest version of this baseline.
//
// No epsilon: the classic |det| < 1e-8 rejection is scale dependent (it drops small but
// valid triangles). Only det == 0 (ray parallel to the plane, or a degenerate triangle) is
// a miss; every comparison is written so that NaN fails it.
#pragma once

#include <algorithm>
#include <cstddef>

#include <glint/core/math.hpp>
#include <glint/intersection/triangle.hpp>

namespace glint {

template <Scalar T>
struct MollerTrumbore {
    using scalar_type = T;
    using RayData = detail::PlainRay<T>;
    static constexpr const char* name = "MollerTrumbore";
    static constexpr bool uses_frame = false;
    static constexpr int field_count = 9;

    Vec3<T> v0{0}, e1{0}, e2{0};

    /// Degenerate triangles (|e1 x e2| <= 2^-60 * longest edge^2) get zero edges: det = 0,
    /// never a hit.
    static MollerTrumbore build(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
        MollerTrumbore r;
        r.v0 = Vec3<T>(a);
        if (detail::degenerate_triangle(a, b, c)) return r;
        r.e1 = Vec3<T>(b - a);
        r.e2 = Vec3<T>(c - a);
        return r;
    }

    static RayData prepare(const Ray<T>& r) { return RayData::from(r); }

    /// The test, written once for the scalar and the batch path: x = (v0, e1, e2).
    /// Bitwise &, not &&: with && GCC vectorizes the batch loop only with AVX-512 masks;
    /// on AVX2 it compiled to scalar code with a branch per condition.
    [[gnu::always_inline]] static bool test(const T (&x)[field_count], const RayData& r, T& t, T& u, T& v) {
        const T e1x = x[3], e1y = x[4], e1z = x[5];
        const T e2x = x[6], e2y = x[7], e2z = x[8];
        const T px = r.d.y * e2z - r.d.z * e2y;
        const T py = r.d.z * e2x - r.d.x * e2z;
        const T pz = r.d.x * e2y - r.d.y * e2x;
        const T det = e1x * px + e1y * py + e1z * pz;
        const T inv = T(1) / det;
        const T sx = r.o.x - x[0], sy = r.o.y - x[1], sz = r.o.z - x[2];
        u = (sx * px + sy * py + sz * pz) * inv;
        const T qx = sy * e1z - sz * e1y;
        const T qy = sz * e1x - sx * e1z;
        const T qz = sx * e1y - sy * e1x;
        v = (r.d.x * qx + r.d.y * qy + r.d.z * qz) * inv;
        t = (e2x * qx + e2y * qy + e2z * qz) * inv;
        return (det != T(0)) & (u >= T(0)) & (v >= T(0)) & (u + v <= T(1)) & (t > r.tmin) & (t < r.tmax);
    }

    bool intersect(const RayData& r, TriangleHit<T>& hit) const { return detail::test_record(*this, r, hit); }

    void store(T* out) const {
        for (int k = 0; k < 3; ++k) {
            out[k] = v0[k];
            out[3 + k] = e1[k];
            out[6 + k] = e2[k];
        }
    }
    static MollerTrumbore load(const SoaView<T, field_count>& v, std::size_t i) {
        MollerTrumbore r;
        for (int k = 0; k < 3; ++k) {
            r.v0[k] = *v.field(k, i);
            r.e1[k] = *v.field(3 + k, i);
            r.e2[k] = *v.field(6 + k, i);
        }
        return r;
    }

    static void batch(const SoaView<T, field_count>& v, std::size_t first, std::size_t n,
                      const RayData& r, T* ts, T* us, T* vs) {
        detail::test_lanes<MollerTrumbore>(v, first, n, r, ts, us, vs);
    }
};

}  // namespace glint
