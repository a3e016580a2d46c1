// cli/flags.hpp: the command-line conventions of glint's programs (glint-render, the
// examples and the benchmarks). Not part of the library: a program that includes glint's
// headers parses its own command line.
//
//   cli::App app("bench_trees: the wide BVH against Embree");
//   cli::number(app, "--reps", o.reps, 1, 1000, "timed repetitions");
//   cli::choice(app, "--tonemap", o.tonemap, std::span<const Choice<Tonemap>>(tonemaps), "tonemap", "PNG preview");
//   cli::flag(app, "--csv-only", o.csv_only, "no table, only the CSV");
//   if (!cli::parse(app, argc, argv)) return 0;   // --help or --version printed
//
// Every flag takes its value as `--flag value` or `--flag=value`; a flag given twice keeps
// the last value (cli::texts collects every one). A number is parsed whole (no trailing text,
// finite) and range checked, and a name is looked up in its choice table, while the command
// line is parsed: a bad value stops the program before it reads a file, with a glint::Error
// naming the flag, the value and what it expects ("--size: expects an integer in
// [1, 16384], got '100000'"). A flag that takes no value given one (--aov=1) is an error.
//
// Help lists the flags under their groups, each with its value's type, its default and its
// help text. Values are handed to their flags after the whole line is read, in the order the
// flags were added (so `--width 24 --size 8` and `--size 8 --width 24` give the same width:
// --size is added first), and the first value a flag rejects stops the parse.
//
// The parser is this project's own (cli/flags.cpp): CLI11, which it replaced, was most of
// that file's compile time for the few conventions above (docs/hardening.md).
#pragma once

#include <charconv>
#include <cmath>
#include <concepts>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <glint/tracer/choice.hpp>

namespace glint::cli {

/// One flag of an App, to chain settings on: `->group("Camera")`; given() after parsing.
class Flag {
public:
    /// The heading the flag is listed under in --help.
    Flag* group(const std::string& name) {
        group_ = name;
        return this;
    }
    /// Whether the command line gave the flag (after parse()).
    bool given() const { return !values_.empty(); }

private:
    friend class App;
    std::string name_, help_, type_, default_, group_;
    std::function<std::string(const std::string&)> set_;  // a flag with a value
    std::function<void()> set_flag_;                      // a flag without one
    bool repeat_ = false;
    std::vector<std::string> values_;  // as given (a flag without a value: one empty entry)
};

/// A program's command line: its description, its flags, --help and --version.
class App {
public:
    explicit App(const std::string& description);
    ~App();
    App(const App&) = delete;
    App& operator=(const App&) = delete;

    /// Adds --version, printing `text`.
    void version(const std::string& text);
    /// A flag with a value: `set` parses and stores one value and returns "" or what was wrong
    /// ("expects ..., got '...'"). `type` and `default_text` are shown by --help; `repeat`:
    /// the flag may be given several times, `set` called for each value in order.
    Flag* value(const std::string& flag, std::function<std::string(const std::string&)> set, const std::string& help,
                const std::string& type, const std::string& default_text, bool repeat = false);
    /// A flag without a value: `set` runs when it is given.
    Flag* flag(const std::string& flag, std::function<void()> set, const std::string& help);
    /// Parses (see cli::parse).
    bool parse(int argc, const char* const* argv);

private:
    Flag* find(std::string_view name);
    std::string help(const std::string& program) const;
    std::string description_, version_;
    std::vector<std::unique_ptr<Flag>> flags_;
};

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

/// A number as --help and the errors show it ("0.05", "16384").
template <class N>
std::string number_text(N x) {
    if constexpr (std::floating_point<N>) {
        char buf[32];
        const auto r = std::to_chars(buf, buf + sizeof buf, x);
        return std::string(buf, r.ptr);
    } else {
        return std::to_string(x);
    }
}

/// What a number flag expects: "an integer in [1, 16384]".
template <class N>
std::string number_range(N lo, N hi) {
    return std::string(std::floating_point<N> ? "a number" : "an integer") + " in [" + number_text(lo) + ", " +
           number_text(hi) + "]";
}

/// A flag whose value is an N in [lo, hi], handed to `set` (for a value that sets several
/// fields, or an optional one); `help` states the default.
template <class N, class Set>
Flag* number_to(App& app, const std::string& flag, Set set, N lo, N hi, const std::string& help,
                const std::string& default_text = "") {
    const std::string range = number_range(lo, hi);
    return app.value(
        flag,
        [set = std::move(set), lo, hi, range](const std::string& text) {
            N x{};
            if (!parse_number(text, lo, hi, x)) return "expects " + range + ", got '" + text + "'";
            set(x);
            return std::string();
        },
        help + " (" + range + ")", std::floating_point<N> ? "NUMBER" : "INT", default_text);
}

/// A flag whose value is an N in [lo, hi], written to `target` (left as is when the flag is
/// absent; its value now shows in --help as the default).
template <class N>
Flag* number(App& app, const std::string& flag, N& target, N lo, N hi, const std::string& help) {
    return number_to<N>(app, flag, [&target](N x) { target = x; }, lo, hi, help, number_text(target));
}

/// A flag whose value is a comma-separated list of Ns in [lo, hi] ("100,1000,5000"), which
/// replaces `target` (its value now shows in --help as the default).
template <class N>
Flag* numbers(App& app, const std::string& flag, std::vector<N>& target, N lo, N hi, const std::string& help) {
    std::string shown;
    for (const N x : target) {
        if (!shown.empty()) shown += ',';
        shown += number_text(x);
    }
    const std::string range = number_range(lo, hi);
    const auto set = [&target, lo, hi, range](const std::string& text) {
        std::vector<N> list;
        for (std::size_t p = 0; p <= text.size();) {
            const std::size_t q = std::min(text.find(',', p), text.size());
            N x{};
            if (!parse_number(std::string_view(text).substr(p, q - p), lo, hi, x))
                return "expects a comma-separated list, each " + range + ", got '" + text + "'";
            list.push_back(x);
            p = q + 1;
        }
        target = std::move(list);
        return std::string();
    };
    return app.value(flag, set, help + " (each " + range + ")", "LIST", shown);
}

/// A flag whose value is a name of `table`, written to `target` (`what` names the table in
/// the error: "unknown tonemap 'x' (clamp, reinhard)"); the names and their help lines follow
/// the flag's help.
template <class Make>
Flag* choice(App& app, const std::string& flag, std::string& target, std::span<const Choice<Make>> table,
             const std::string& what, const std::string& help) {
    std::string names = choice_usage(table, 4);
    names.pop_back();  // the last line's newline
    return app.value(
        flag,
        [&target, table, what](const std::string& text) {
            try {
                find_choice(table, what, text);
            } catch (const Error& e) {
                return std::string(e.what());
            }
            target = text;
            return std::string();
        },
        help + ":\n" + names, "NAME", target);
}

/// A flag whose value is any text, written to `target`: a file name (`type` as --help shows
/// it), or a name the program checks itself (against a table with a grammar).
inline Flag* text(App& app, const std::string& flag, std::string& target, const std::string& help,
                  const std::string& type = "FILE") {
    const auto set = [&target](const std::string& t) {
        target = t;
        return std::string();
    };
    return app.value(flag, set, help, type, target);
}

/// A flag that may be given several times, each value appended to `target`.
inline Flag* texts(App& app, const std::string& flag, std::vector<std::string>& target, const std::string& help,
                   const std::string& type = "FILE") {
    const auto add = [&target](const std::string& t) {
        target.push_back(t);
        return std::string();
    };
    return app.value(flag, add, help, type, "", true);
}

/// Throws glint::Error unless `path` can be written: its folder exists and is writable, and
/// the file, if it exists, is writable and not a folder.
void check_writable(const std::string& path);

/// A flag whose value is a file the program writes (checked by check_writable while the
/// command line is parsed, so that a long run is not lost), written to `target`.
Flag* output(App& app, const std::string& flag, std::string& target, const std::string& help);

/// A flag whose value is an existing folder, written to `target`.
Flag* folder(App& app, const std::string& flag, std::string& target, const std::string& help);

/// A flag without a value that sets `target` to true.
inline Flag* flag(App& app, const std::string& flag, bool& target, const std::string& help) {
    return app.flag(flag, [&target] { target = true; }, help);
}

/// Parses the command line. Returns false after printing --help or --version (the program
/// then exits with 0); throws glint::Error naming the flag and the value for a bad one.
inline bool parse(App& app, int argc, const char* const* argv) { return app.parse(argc, argv); }

/// parse() for a program's main: exits with 0 after --help or --version, and with 2 after
/// printing "<program>: <error>" for a bad command line.
void parse_or_exit(App& app, int argc, const char* const* argv, const std::string& program);

}  // namespace glint::cli
