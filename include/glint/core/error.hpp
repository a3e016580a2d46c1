// glint/core/error.hpp: the one exception type glint throws.
//
// Loading and configuration errors throw glint::Error with a message a user can act on
// (which file, which line, what was expected). Hot paths never throw.
#pragma once

#include <stdexcept>
#include <string>

namespace glint {

/// The exception glint's loaders and configuration checks throw; what() is a message naming
/// the file, line or setting at fault and what was expected. Catch it as std::runtime_error too.
class Error : public std::runtime_error {
public:
    /// An error carrying the user-facing message `what`.
    explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace glint
