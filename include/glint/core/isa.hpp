// glint/core/isa.hpp: the instruction sets glint's hot kernels are compiled for, and the one
// the CPU running the program supports, found once at run time.
//
// A header-only library is compiled with its user's flags, which for a distribution package
// or any renderer built for baseline x86-64 means SSE2 only. The kernels that pay for wider
// vectors (the wide BVH's traversal with its leaf tests) are therefore compiled several
// times: for the flags given, for AVX2 through GCC's and Clang's `target` attribute (no
// compiler flag needed), and (GCC) for AVX-512. A tree picks one when it is built
// (best_isa()) and branches on it once per query, never per node. A build with -march flags
// that include AVX2 compiles only the flags' kernels: the others would never be chosen.
#pragma once

#include <optional>
#include <string_view>
#include <type_traits>

namespace glint {

/// Kernels by instruction set, ordered: a CPU that runs one runs those before it.
enum class Isa : unsigned char {
    portable,  // plain C++ loops (the reference; any CPU)
    sse2,      // 128-bit vectors (every x86-64 CPU)
    avx2,      // 256-bit vectors (x86-64 from 2013 on)
    avx512,    // the AVX2 kernels compiled for AVX-512 F/VL/BW/DQ: 32 vector registers, mask
               // registers, EVEX forms; the same hits (GCC only: see GLINT_TARGET_AVX512)
};

/// Every kernel set, in order (for tests and comparisons that try each one isa_supported()).
inline constexpr Isa all_isas[] = {Isa::portable, Isa::sse2, Isa::avx2, Isa::avx512};

/// An instruction set as a type, for the callables a dispatch hands the kernels to.
template <Isa I>
using IsaTag = std::integral_constant<Isa, I>;

inline const char* isa_name(Isa isa) {
    switch (isa) {
        case Isa::portable: return "portable";
        case Isa::sse2: return "sse2";
        case Isa::avx2: return "avx2";
        case Isa::avx512: return "avx512";
    }
    return "?";
}

/// The kernel set named `name` (as isa_name() writes it), or none.
inline std::optional<Isa> isa_from_name(std::string_view name) {
    for (Isa isa : all_isas)
        if (name == isa_name(isa)) return isa;
    return std::nullopt;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define GLINT_X86 1
/// Compiles the function it precedes for AVX2, whatever the translation unit's flags. Not
/// for FMA: contracting a * b + c would round the leaf tests differently from the other
/// kernels of the same build, and every kernel of a build gives the same hits.
#define GLINT_TARGET_AVX2 [[gnu::target("avx2,bmi,bmi2,popcnt")]]
#if defined(__clang__)
#define GLINT_AVX512_KERNELS 0
#else
#define GLINT_AVX512_KERNELS 1
/// Compiles the function it precedes for AVX-512 (F, VL, BW, DQ) without contracting a * b + c
/// into FMAs (AVX-512F implies them): the AVX2 kernels' arithmetic, rounded as theirs, with
/// twice the registers. GCC only: Clang has no per-function contraction switch, and its
/// default contracts the kernels' expressions where the target has FMA.
#define GLINT_TARGET_AVX512 \
    [[gnu::target("avx2,bmi,bmi2,popcnt,avx512f,avx512vl,avx512bw,avx512dq"), gnu::optimize("fp-contract=off")]]
#endif
#else
#define GLINT_AVX512_KERNELS 0
#define GLINT_X86 0
#define GLINT_TARGET_AVX2
#endif

/// A small kernel written with AVX2 intrinsics: always inlined where the flags compile AVX2
/// anyway; elsewhere compiled for AVX2 and inlined into its AVX2 caller by that caller's
/// `flatten` (GCC and Clang refuse always_inline across targets).
#if defined(__AVX2__)
#define GLINT_KERNEL_AVX2 [[gnu::always_inline]]
#else
#define GLINT_KERNEL_AVX2 GLINT_TARGET_AVX2
#endif

/// The kernels the translation unit's own flags compile (what -march gives).
inline constexpr Isa compiled_isa =
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__) && defined(__AVX512DQ__)
    Isa::avx512;
#elif defined(__AVX2__)
    Isa::avx2;
#elif GLINT_X86
    Isa::sse2;
#else
    Isa::portable;
#endif

/// The best kernels this build has that the running CPU (and its operating system) supports;
/// checked once. A build whose flags give AVX2 or more has the flags' kernels only.
inline Isa best_isa() {
#if GLINT_X86
    if constexpr (compiled_isa >= Isa::avx2) return compiled_isa;
    static const Isa isa = [] {
        __builtin_cpu_init();
        const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi2") &&
                          __builtin_cpu_supports("popcnt");
        const bool avx512 = GLINT_AVX512_KERNELS && avx2 && __builtin_cpu_supports("avx512f") &&
                            __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
                            __builtin_cpu_supports("avx512dq");
        return avx512 ? Isa::avx512 : avx2 ? Isa::avx2 : Isa::sse2;
    }();
    return isa;
#else
    return Isa::portable;
#endif
}

/// Whether this build and this CPU can run `isa`'s kernels. A build whose flags give AVX2 or
/// AVX-512 compiles those kernels only (the CPU it is built for runs them); a build without
/// compiles the portable and SSE2 kernels and, through the `target` attribute, AVX2's and
/// (GCC) AVX-512's for CPUs with them.
inline bool isa_supported(Isa isa) {
    if constexpr (compiled_isa >= Isa::avx2) return isa == compiled_isa;
    return isa <= best_isa() || isa <= compiled_isa;
}

}  // namespace glint
