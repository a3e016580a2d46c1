// glint/occluders/predicates.hpp: robust orient3d and insphere for the Delaunay
// tetrahedralization (Szécsi 2009, §5.2: the Bowyer-Watson mesh of surface
// points; the text assumes exact geometry, gridded and cospherical samples do not have it).
//
// Shewchuk-style adaptive predicates, written for glint: a floating-point filter (the
// determinant of the differences in double with Shewchuk's a-priori error bounds
// errboundA, which cover the rounding of the differences too) decides almost every call; when
// |det| is below the bound, the determinant of the raw coordinates is evaluated exactly in
// expansion arithmetic (Shewchuk 1997: two_sum, two_product via fma, fast expansion sum
// and scale expansion with zero elimination). Exact evaluation uses fixed-capacity
// expansions on the stack: no allocation, no throw. Inputs must be finite doubles whose
// products do not overflow or underflow (|coordinate| in roughly [1e-60, 1e60] or 0).
//
// Sign conventions (as Shewchuk's, with the orientation flipped to the right-handed sense):
//   orient3d(a, b, c, d) > 0  when d lies on the side of plane (a, b, c) into which
//                             (b - a) x (c - a) points, i.e. det[b-a; c-a; d-a] > 0;
//   insphere(a, b, c, d, e) > 0 when e lies strictly inside the sphere through a, b, c, d,
//                             provided orient3d(a, b, c, d) > 0.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>

#include <glint/core/math.hpp>

namespace glint {

namespace detail {

/// A nonoverlapping expansion of at most N doubles, increasing magnitude, zeros removed.
template <std::size_t N>
struct Expansion {
    std::array<double, N> e;
    std::size_t n = 0;
    double sign() const { return n == 0 ? 0.0 : (e[n - 1] > 0 ? 1.0 : -1.0); }
};

inline void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    const double bv = x - a, av = x - bv;
    y = (a - av) + (b - bv);
}

inline Expansion<2> product(double a, double b) {
    Expansion<2> r;
    const double p = a * b, err = std::fma(a, b, -p);
    if (err != 0) r.e[r.n++] = err;
    if (p != 0) r.e[r.n++] = p;
    return r;
}

/// Shewchuk's fast_expansion_sum_zeroelim (h = e + f).
template <std::size_t A, std::size_t B>
Expansion<A + B> add(const Expansion<A>& e, const Expansion<B>& f) {
    Expansion<A + B> h;
    if (e.n == 0) {
        for (std::size_t i = 0; i < f.n; ++i) h.e[i] = f.e[i];
        h.n = f.n;
        return h;
    }
    if (f.n == 0) {
        for (std::size_t i = 0; i < e.n; ++i) h.e[i] = e.e[i];
        h.n = e.n;
        return h;
    }
    std::size_t ei = 0, fi = 0;
    double enow = e.e[0], fnow = f.e[0], q, qnew, hh;
    if ((fnow > enow) == (fnow > -enow)) {
        q = enow;
        enow = ++ei < e.n ? e.e[ei] : 0;
    } else {
        q = fnow;
        fnow = ++fi < f.n ? f.e[fi] : 0;
    }
    auto fast_two_sum = [](double a, double b, double& x, double& y) {
        x = a + b;
        y = b - (x - a);
    };
    if (ei < e.n && fi < f.n) {
        if ((fnow > enow) == (fnow > -enow)) {
            fast_two_sum(enow, q, qnew, hh);
            enow = ++ei < e.n ? e.e[ei] : 0;
        } else {
            fast_two_sum(fnow, q, qnew, hh);
            fnow = ++fi < f.n ? f.e[fi] : 0;
        }
        q = qnew;
        if (hh != 0) h.e[h.n++] = hh;
        while (ei < e.n && fi < f.n) {
            if ((fnow > enow) == (fnow > -enow)) {
                two_sum(q, enow, qnew, hh);
                enow = ++ei < e.n ? e.e[ei] : 0;
            } else {
                two_sum(q, fnow, qnew, hh);
                fnow = ++fi < f.n ? f.e[fi] : 0;
            }
            q = qnew;
            if (hh != 0) h.e[h.n++] = hh;
        }
    }
    while (ei < e.n) {
        two_sum(q, enow, qnew, hh);
        enow = ++ei < e.n ? e.e[ei] : 0;
        q = qnew;
        if (hh != 0) h.e[h.n++] = hh;
    }
    while (fi < f.n) {
        two_sum(q, fnow, qnew, hh);
        fnow = ++fi < f.n ? f.e[fi] : 0;
        q = qnew;
        if (hh != 0) h.e[h.n++] = hh;
    }
    if (q != 0 || h.n == 0) h.e[h.n++] = q;
    if (h.n == 1 && h.e[0] == 0) h.n = 0;
    return h;
}

/// Shewchuk's scale_expansion_zeroelim (h = e * b).
template <std::size_t A>
Expansion<2 * A> scale(const Expansion<A>& e, double b) {
    Expansion<2 * A> h;
    if (e.n == 0 || b == 0) return h;
    double q = e.e[0] * b, hh = std::fma(e.e[0], b, -q), sum, prod, perr;
    if (hh != 0) h.e[h.n++] = hh;
    for (std::size_t i = 1; i < e.n; ++i) {
        prod = e.e[i] * b;
        perr = std::fma(e.e[i], b, -prod);
        two_sum(q, perr, sum, hh);
        if (hh != 0) h.e[h.n++] = hh;
        // fast_two_sum(prod, sum): |prod| >= |sum| holds for nonoverlapping input
        q = prod + sum;
        hh = sum - (q - prod);
        if (hh != 0) h.e[h.n++] = hh;
    }
    if (q != 0) h.e[h.n++] = q;
    return h;
}

template <std::size_t A, std::size_t B>
Expansion<A + B> sub(const Expansion<A>& e, Expansion<B> f) {
    for (std::size_t i = 0; i < f.n; ++i) f.e[i] = -f.e[i];
    return add(e, f);
}

/// Product of two expansions: sum over f's components of e scaled by them.
template <std::size_t A, std::size_t B>
Expansion<2 * A * B> multiply(const Expansion<A>& e, const Expansion<B>& f) {
    Expansion<2 * A * B> h;
    for (std::size_t i = 0; i < f.n; ++i) {
        const Expansion<2 * A> s = scale(e, f.e[i]);
        // h holds at most 2*A*i components so far; add into a same-capacity result.
        Expansion<2 * A * B> t;
        const Expansion<2 * A * B + 2 * A> full = add(h, s);
        for (std::size_t k = 0; k < full.n; ++k) t.e[k] = full.e[k];
        t.n = full.n;
        h = t;
    }
    return h;
}

/// det [[ax ay 1] [bx by 1] [cx cy 1]]-style 2x2 minor a.x*b.y - b.x*a.y, exact.
inline Expansion<4> minor2(double ax, double ay, double bx, double by) {
    return sub(product(ax, by), product(bx, ay));
}

/// det[p; q; r] (rows p, q, r), exact, by minors along the z column.
inline Expansion<24> det3(const Vec3d& p, const Vec3d& q, const Vec3d& r) {
    const Expansion<16> s1 = add(scale(minor2(q.x, q.y, r.x, r.y), p.z), scale(minor2(r.x, r.y, p.x, p.y), q.z));
    return add(s1, scale(minor2(p.x, p.y, q.x, q.y), r.z));
}

/// Exact orient3d on raw coordinates: det[b-a; c-a; d-a] expanded as the 4x4 determinant
/// with a column of ones (Shewchuk's orient3dexact, sign adjusted).
inline double orient3d_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    // det[b-a; c-a; d-a] = det[b;c;d] - det[a;c;d] + det[a;b;d] - det[a;b;c].
    const auto bcd = det3(b, c, d), acd = det3(a, c, d), abd = det3(a, b, d), abc = det3(a, b, c);
    return add(sub(bcd, acd), sub(abd, abc)).sign();
}

/// Exact insphere on raw coordinates: the 5x5 determinant with rows [p, |p|^2, 1],
/// expanded along the lift column; the cofactors are the exact 4x4 orientation dets.
inline double insphere_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d,
                             const Vec3d& e) {
    // O(p,q,r,s) = det[q-p; r-p; s-p] as an expansion.
    auto orient = [&](const Vec3d& p, const Vec3d& q, const Vec3d& r, const Vec3d& s) {
        return add(sub(det3(q, r, s), det3(p, r, s)), sub(det3(p, q, s), det3(p, q, r)));
    };
    auto lift = [](const Vec3d& p) { return add(add(product(p.x, p.x), product(p.y, p.y)), product(p.z, p.z)); };
    // insphere(a,b,c,d,e) = sum_i (-1)^i |p_i|^2 O(others) with the sign chosen so that it is
    // positive for e inside when O(a,b,c,d) > 0:
    //   I = |e|^2 O(a,b,c,d) - |d|^2 O(a,b,c,e) + |c|^2 O(a,b,d,e) - |b|^2 O(a,c,d,e) + |a|^2 O(b,c,d,e)
    // negated (the lift of an inside point is below the lifted sphere plane).
    const auto t_e = multiply(orient(a, b, c, d), lift(e));
    const auto t_d = multiply(orient(a, b, c, e), lift(d));
    const auto t_c = multiply(orient(a, b, d, e), lift(c));
    const auto t_b = multiply(orient(a, c, d, e), lift(b));
    const auto t_a = multiply(orient(b, c, d, e), lift(a));
    const auto s = add(add(sub(t_e, t_d), sub(t_c, t_b)), t_a);
    return -s.sign();
}

}  // namespace detail

/// Sign of det[b-a; c-a; d-a] (+1, 0, -1), exact for finite double input.
inline int orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    const double adx = a.x - d.x, bdx = b.x - d.x, cdx = c.x - d.x;
    const double ady = a.y - d.y, bdy = b.y - d.y, cdy = c.y - d.y;
    const double adz = a.z - d.z, bdz = b.z - d.z, cdz = c.z - d.z;
    const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
    const double cdxady = cdx * ady, adxcdy = adx * cdy;
    const double adxbdy = adx * bdy, bdxady = bdx * ady;
    // Shewchuk's orient3d(a,b,c,d) = det[a-d; b-d; c-d]; ours is det[b-a; c-a; d-a] = -that.
    const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
    const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                             (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                             (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
    constexpr double eps = 0x1p-53;
    constexpr double errbound = (7.0 + 56.0 * eps) * eps;
    if (det > errbound * permanent) return -1;
    if (-det > errbound * permanent) return 1;
    const double s = detail::orient3d_exact(a, b, c, d);
    return s > 0 ? 1 : (s < 0 ? -1 : 0);
}

/// +1 when e is strictly inside the sphere through a, b, c, d (orient3d(a,b,c,d) > 0),
/// 0 on it, -1 outside; exact for finite double input.
inline int insphere(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d, const Vec3d& e) {
    const double aex = a.x - e.x, bex = b.x - e.x, cex = c.x - e.x, dex = d.x - e.x;
    const double aey = a.y - e.y, bey = b.y - e.y, cey = c.y - e.y, dey = d.y - e.y;
    const double aez = a.z - e.z, bez = b.z - e.z, cez = c.z - e.z, dez = d.z - e.z;
    const double aexbey = aex * bey, bexaey = bex * aey, ab = aexbey - bexaey;
    const double bexcey = bex * cey, cexbey = cex * bey, bc = bexcey - cexbey;
    const double cexdey = cex * dey, dexcey = dex * cey, cd = cexdey - dexcey;
    const double dexaey = dex * aey, aexdey = aex * dey, da = dexaey - aexdey;
    const double aexcey = aex * cey, cexaey = cex * aey, ac = aexcey - cexaey;
    const double bexdey = bex * dey, dexbey = dex * bey, bd = bexdey - dexbey;
    const double abc = aez * bc - bez * ac + cez * ab;
    const double bcd = bez * cd - cez * bd + dez * bc;
    const double cda = cez * da + dez * ac + aez * cd;
    const double dab = dez * ab + aez * bd + bez * da;
    const double alift = aex * aex + aey * aey + aez * aez;
    const double blift = bex * bex + bey * bey + bez * bez;
    const double clift = cex * cex + cey * cey + cez * cez;
    const double dlift = dex * dex + dey * dey + dez * dez;
    // Shewchuk's insphere (positive inside for his positively oriented a,b,c,d, which is our
    // negative orientation): flip.
    const double det = (dlift * abc - clift * dab) + (blift * cda - alift * bcd);
    const double aezp = std::abs(aez), bezp = std::abs(bez), cezp = std::abs(cez), dezp = std::abs(dez);
    const double aexbeyp = std::abs(aexbey), bexaeyp = std::abs(bexaey);
    const double bexceyp = std::abs(bexcey), cexbeyp = std::abs(cexbey);
    const double cexdeyp = std::abs(cexdey), dexceyp = std::abs(dexcey);
    const double dexaeyp = std::abs(dexaey), aexdeyp = std::abs(aexdey);
    const double aexceyp = std::abs(aexcey), cexaeyp = std::abs(cexaey);
    const double bexdeyp = std::abs(bexdey), dexbeyp = std::abs(dexbey);
    const double permanent =
        ((cexdeyp + dexceyp) * bezp + (dexbeyp + bexdeyp) * cezp + (bexceyp + cexbeyp) * dezp) * alift +
        ((dexaeyp + aexdeyp) * cezp + (aexceyp + cexaeyp) * dezp + (cexdeyp + dexceyp) * aezp) * blift +
        ((aexbeyp + bexaeyp) * dezp + (bexdeyp + dexbeyp) * aezp + (dexaeyp + aexdeyp) * bezp) * clift +
        ((bexceyp + cexbeyp) * aezp + (cexaeyp + aexceyp) * bezp + (aexbeyp + bexaeyp) * cezp) * dlift;
    constexpr double eps = 0x1p-53;
    constexpr double errbound = (16.0 + 224.0 * eps) * eps;
    if (det > errbound * permanent) return -1;
    if (-det > errbound * permanent) return 1;
    const double s = detail::insphere_exact(a, b, c, d, e);
    return s > 0 ? 1 : (s < 0 ? -1 : 0);
}

}  // namespace glint
