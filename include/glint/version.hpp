// glint/version.hpp: glint's version, the one place it is written (CMakeLists.txt reads it
// from here for the package files).
#pragma once

namespace glint {

inline constexpr int version_major = 0;
inline constexpr int version_minor = 1;
inline constexpr int version_patch = 0;
/// "major.minor.patch".
inline constexpr const char* version_string = "0.1.0";

}  // namespace glint
