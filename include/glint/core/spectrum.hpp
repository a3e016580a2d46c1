// glint/core/spectrum.hpp: a value per wavelength band.
//
// Spectrum<T, N> holds N samples of a spectral quantity (radiance, albedo, throughput) and
// supports elementwise arithmetic. Luminance is a weighted sum of the bands; for RGB the
// default weights are (0.3086, 0.6094, 0.0820), the luminance weights Szécsi 2009, §2.2 uses
// for its spectral Russian roulette (Haeberli's linear-RGB weights). Other N default to the
// plain mean.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

namespace glint {

/// N samples of a spectral quantity of scalar type T (radiance, albedo, throughput), with
/// elementwise arithmetic against spectra and scalars (+, -, *, / and their compound forms;
/// division by a zero band gives inf or NaN as for T). Rgb<T> is N = 3.
template <class T, std::size_t N>
struct Spectrum {
    static_assert(N > 0, "a spectrum needs at least one band");
    /// Number of bands, N.
    static constexpr std::size_t size = N;
    /// The band values, in band order (R, G, B for Rgb); zero-initialized by default.
    std::array<T, N> v{};

    /// All bands zero.
    constexpr Spectrum() = default;
    /// Every band set to `s` (a grey spectrum).
    constexpr explicit Spectrum(T s) { v.fill(s); }
    /// One value per band, in order, each converted to T: Rgb<float>(r, g, b). Needs exactly N
    /// arguments and N > 1 (one argument is the grey constructor).
    template <class... U>
        requires(sizeof...(U) == N && N > 1)
    constexpr Spectrum(U... x) : v{static_cast<T>(x)...} {}

    /// Band i, unchecked: 0 <= i < N.
    constexpr T& operator[](std::size_t i) { return v[i]; }
    /// Read-only band i, unchecked: 0 <= i < N.
    constexpr const T& operator[](std::size_t i) const { return v[i]; }

#define GLINT_SPECTRUM_OP(op)                                                          \
    constexpr Spectrum& operator op##=(const Spectrum& o) {                            \
        for (std::size_t i = 0; i < N; ++i) v[i] op## = o.v[i];                        \
        return *this;                                                                  \
    }                                                                                  \
    constexpr Spectrum& operator op##=(T s) {                                          \
        for (std::size_t i = 0; i < N; ++i) v[i] op## = s;                             \
        return *this;                                                                  \
    }                                                                                  \
    friend constexpr Spectrum operator op(Spectrum a, const Spectrum& b) { return a op## = b; } \
    friend constexpr Spectrum operator op(Spectrum a, T s) { return a op## = s; }      \
    friend constexpr Spectrum operator op(T s, const Spectrum& b) {                    \
        Spectrum r;                                                                    \
        for (std::size_t i = 0; i < N; ++i) r.v[i] = s op b.v[i];                      \
        return r;                                                                      \
    }
    GLINT_SPECTRUM_OP(+)
    GLINT_SPECTRUM_OP(-)
    GLINT_SPECTRUM_OP(*)
    GLINT_SPECTRUM_OP(/)
#undef GLINT_SPECTRUM_OP

    /// Every band negated.
    constexpr Spectrum operator-() const { return T(0) - *this; }
    /// Exact band-by-band equality (no tolerance; a NaN band is unequal to everything).
    friend constexpr bool operator==(const Spectrum&, const Spectrum&) = default;

    /// Largest band value.
    constexpr T max() const { return *std::max_element(v.begin(), v.end()); }
    /// Smallest band value.
    constexpr T min() const { return *std::min_element(v.begin(), v.end()); }
    /// Sum of the band values.
    constexpr T sum() const {
        T s = 0;
        for (T x : v) s += x;
        return s;
    }
    /// Average band value, sum() / N (unweighted, unlike luminance()).
    constexpr T mean() const { return sum() / T(N); }
    /// True when every band is exactly zero (e.g. a path whose throughput died).
    constexpr bool is_zero() const {
        return std::all_of(v.begin(), v.end(), [](T x) { return x == T(0); });
    }
    /// True when no band is infinite or NaN; the check renderers run before accumulating.
    bool is_finite() const {
        return std::all_of(v.begin(), v.end(), [](T x) { return std::isfinite(x); });
    }

    /// Default luminance weights: Szécsi 2009, §2.2's RGB weights for N = 3, else 1/N each.
    static constexpr Spectrum default_luminance_weights() {
        if constexpr (N == 3) {
            return Spectrum(T(0.3086), T(0.6094), T(0.0820));
        } else {
            return Spectrum(T(1) / T(N));
        }
    }

    /// Weighted sum of the bands.
    constexpr T luminance(const Spectrum& weights = default_luminance_weights()) const {
        T s = 0;
        for (std::size_t i = 0; i < N; ++i) s += weights.v[i] * v[i];
        return s;
    }
};

/// Elementwise maximum and minimum.
template <class T, std::size_t N>
constexpr Spectrum<T, N> max(const Spectrum<T, N>& a, const Spectrum<T, N>& b) {
    Spectrum<T, N> r;
    for (std::size_t i = 0; i < N; ++i) r[i] = std::max(a[i], b[i]);
    return r;
}
template <class T, std::size_t N>
constexpr Spectrum<T, N> min(const Spectrum<T, N>& a, const Spectrum<T, N>& b) {
    Spectrum<T, N> r;
    for (std::size_t i = 0; i < N; ++i) r[i] = std::min(a[i], b[i]);
    return r;
}

/// Three-band red, green, blue spectrum, the one glint's renderers and image writers use.
template <class T> using Rgb = Spectrum<T, 3>;

}  // namespace glint
