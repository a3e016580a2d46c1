// glint/tracer/choice.hpp: a choice by name as one table of {name, help, make} entries (as
// pbrt-v4's Create() functions): the table feeds a command line's usage text and the error for
// an unknown name, and `make` builds what the name stands for (a value, or a function that
// builds it). Tables live next to what they choose among (tracer/scenes.hpp's scenes,
// tracer/named_render.hpp's policies).
#pragma once

#include <algorithm>
#include <cstddef>
#include <span>
#include <string>
#include <string_view>

#include <glint/core/error.hpp>

namespace glint {

/// One entry of a choice table: a name a user types, its one-line description, and what
/// builds the chosen thing. Tables are static arrays, so the strings are literals.
template <class Make>
struct Choice {
    std::string_view name;  ///< What the user types (a command-line value), unique in its table.
    std::string_view help;  ///< One line for the usage text: what the choice is and costs.
    Make make;              ///< The chosen value, or a function that builds it.
};

/// The table's names, "a, b, c".
template <class Make>
std::string choice_names(std::span<const Choice<Make>> table) {
    std::string out;
    for (const auto& c : table) out += (out.empty() ? "" : ", ") + std::string(c.name);
    return out;
}

/// The entry called `name`; throws glint::Error "unknown <what> '<name>' (<names>)" otherwise.
template <class Make>
const Choice<Make>& find_choice(std::span<const Choice<Make>> table, std::string_view what, std::string_view name) {
    for (const auto& c : table)
        if (c.name == name) return c;
    throw Error("unknown " + std::string(what) + " '" + std::string(name) + "' (" + choice_names(table) + ")");
}

/// The table as usage lines: each name and its help, indented by `indent`.
template <class Make>
std::string choice_usage(std::span<const Choice<Make>> table, std::size_t indent = 22) {
    std::string out;
    for (std::size_t i = 0; i < table.size(); ++i) {
        std::string line(indent, ' ');
        line += std::string(table[i].name);
        line.resize(std::max(line.size() + 2, indent + 16), ' ');
        line += std::string(table[i].help);
        out += line + "\n";
    }
    return out;
}

}  // namespace glint
