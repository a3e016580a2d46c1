// glint/core/error.hpp: the one exception type glint throws.
//
// Loading and configuration errors throw glint::Error with a message a user can act on
// (which file, which line, what was expected). Hot paths never throw.
#pragma once

#include <stdexcept>
#include <string>

namespace glint {

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace glint
