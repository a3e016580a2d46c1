// cli/flags.hpp: the command-line conventions of glint's programs (glint-render, the
// examples and the benchmarks), on CLI11 (Debian libcli11-dev). Not part of the library:
// a program that includes glint's headers parses its own command line.
//
//   CLI::App app("bench_trees: the wide BVH against Embree");
//   cli::number(app, "--reps", o.reps, 1, 1000, "timed repetitions");
//   cli::choice(app, "--tonemap", o.tonemap, std::span(tonemaps), "tonemap", "PNG preview");
//   if (!cli::parse(app, argc, argv)) return 0;   // --help or --version printed
//
// Every flag takes its value as `--flag value` or `--flag=value`. A number is parsed whole
// (no trailing text, finite) and range checked, and a name is looked up in its choice table,
// while the command line is parsed: a bad value stops the program before it reads a file,
// with an Error naming the flag, the value and what it expects ("--size: expects an integer
// in [1, 16384], got '100000'").
#pragma once

#include <charconv>
#include <cmath>
#include <concepts>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

#include <CLI/CLI.hpp>

#include <glint/core/error.hpp>
#include <glint/tracer/choice.hpp>

namespace glint::cli {

/// `text` parsed whole as an N (std::from_chars: no sign '+', no trailing text); false for
/// anything else, for a non-finite float, and outside [lo, hi].
template <class N>
bool parse_number(std::string_view text, N lo, N hi, N& out) {
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
    if (ec != std::errc{} || end != text.data() + text.size()) return false;
    if constexpr (std::floating_point<N>)
        if (!std::isfinite(out)) return false;
    return out >= lo && out <= hi;
}

/// What a number flag expects, for its errors and its help: "an integer in [1, 16384]".
template <class N>
std::string number_range(N lo, N hi) {
    auto text = [](N x) {
        if constexpr (std::floating_point<N>) {
            char buf[32];
            std::snprintf(buf, sizeof buf, "%g", double(x));
            return std::string(buf);
        } else {
            return std::to_string(x);
        }
    };
    return std::string(std::floating_point<N> ? "a number" : "an integer") + " in [" + text(lo) + ", " + text(hi) + "]";
}

/// The check of a number flag: its value parsed whole as an N in [lo, hi].
template <class N>
CLI::Validator number_check(N lo, N hi) {
    return CLI::Validator(
        [lo, hi, range = number_range(lo, hi)](std::string& text) {
            N x{};
            return parse_number(text, lo, hi, x) ? std::string() : "expects " + range + ", got '" + text + "'";
        },
        "", "range");
}

/// A flag whose value is an N in [lo, hi], written to `target` (left as is when the flag is
/// absent; its default shows in --help). Returns the option, e.g. to ask ->count().
template <class N>
CLI::Option* number(CLI::App& app, const std::string& flag, N& target, N lo, N hi, const std::string& help) {
    return app.add_option(flag, target, help + " (" + number_range(lo, hi) + ")")
        ->check(number_check(lo, hi))
        ->capture_default_str();
}

/// A flag whose value is an N in [lo, hi], handed to `set` (for a value that sets several
/// fields, or an optional one); `help` states the default.
template <class N, class Set>
CLI::Option* number_to(CLI::App& app, const std::string& flag, Set set, N lo, N hi, const std::string& help) {
    return app.add_option_function<N>(flag, std::move(set), help + " (" + number_range(lo, hi) + ")")
        ->check(number_check(lo, hi));
}

/// A flag whose value is a name of `table` (`what` names the table in the error: "unknown
/// tonemap 'x' (clamp, reinhard)"); the table's names and help lines follow the flag's help.
template <class Make>
CLI::Option* choice(CLI::App& app, const std::string& flag, std::string& target, std::span<const Choice<Make>> table,
                    const std::string& what, const std::string& help) {
    CLI::Validator check(
        [table, what](std::string& text) {
            for (const auto& c : table)
                if (c.name == text) return std::string();
            return "unknown " + what + " '" + text + "' (" + choice_names(table) + ")";
        },
        "", "choice");
    std::string names = choice_usage(table, 4);
    names.pop_back();  // the last line's newline
    return app.add_option(flag, target, help + ":\n" + names)->check(check)->capture_default_str()->type_name("NAME");
}

/// A flag whose value is any text: a file name (as --help shows it), or a name that the
/// program checks itself (against a table with a grammar, such as roulette+estimate).
inline CLI::Option* text(CLI::App& app, const std::string& flag, std::string& target, const std::string& help) {
    return app.add_option(flag, target, help)->capture_default_str()->type_name("FILE");
}

/// Parses the command line. Returns false after printing --help or --version (the program
/// then exits with 0); throws glint::Error naming the flag and the value for a bad one.
inline bool parse(CLI::App& app, int argc, const char* const* argv) {
    for (int i = 1; i < argc; ++i) {  // --flag=value for a flag that takes none: an error, not a value
        const std::string_view a = argv[i];
        const auto eq = a.find('=');
        if (!a.starts_with("--") || eq == std::string_view::npos) continue;
        const CLI::Option* o = app.get_option_no_throw(std::string(a.substr(0, eq)));
        if (o != nullptr && o->get_expected_max() == 0)
            throw Error(std::string(a.substr(0, eq)) + " takes no value, got '" + std::string(a) + "'");
    }
    try {
        app.parse(argc, argv);
        return true;
    } catch (const CLI::CallForHelp&) {
        std::fputs(app.help().c_str(), stdout);
    } catch (const CLI::CallForAllHelp&) {
        std::fputs(app.help("", CLI::AppFormatMode::All).c_str(), stdout);
    } catch (const CLI::CallForVersion& v) {
        std::printf("%s\n", v.what());
    } catch (const CLI::ParseError& e) {
        throw Error(std::string(e.what()) + " (see --help)");
    }
    return false;
}

}  // namespace glint::cli
