// cli/flags.cpp: cli/flags.hpp's App on CLI11, the one translation unit that compiles CLI11.
#include "flags.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <utility>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <glint/core/error.hpp>

namespace glint::cli {

Flag* Flag::group(const std::string& name) {
    o_->group(name);
    return this;
}

bool Flag::given() const { return o_->count() > 0; }

App::App(const std::string& description) : app_(std::make_unique<CLI::App>(description)) {}

App::~App() = default;

void App::version(const std::string& text) { app_->set_version_flag("--version", text); }

Flag* App::value(const std::string& flag, std::function<std::string(const std::string&)> set, const std::string& help,
                 const std::string& type, const std::string& default_text, bool repeat) {
    // A single flag keeps its last value (`--size 8 --size 16` reads 16); a repeated one hands
    // each value to `set` in order.
    const auto check = [flag](const std::string& error) {
        if (!error.empty()) throw CLI::ValidationError(flag, error);
    };
    CLI::Option* o = nullptr;
    if (repeat) {
        o = app_->add_option_function<std::vector<std::string>>(
            flag, [set = std::move(set), check](const std::vector<std::string>& values) {
                for (const std::string& v : values) check(set(v));
            }, help);
        o->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)->allow_extra_args(false);
    } else {
        o = app_->add_option_function<std::string>(
            flag, [set = std::move(set), check](const std::string& v) { check(set(v)); }, help);
        o->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    }
    o->type_name(type);
    if (!default_text.empty()) o->default_str(default_text);
    flags_.push_back(std::make_unique<Flag>(o));
    return flags_.back().get();
}

Flag* App::flag(const std::string& flag, std::function<void()> set, const std::string& help) {
    flags_.push_back(std::make_unique<Flag>(app_->add_flag_callback(flag, std::move(set), help)));
    return flags_.back().get();
}

void check_writable(const std::string& path) {
    const auto slash = path.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
    if (access(dir.c_str(), W_OK) != 0)
        throw Error("cannot write '" + path + "': folder '" + dir + "' " + std::strerror(errno));
    if (std::filesystem::is_directory(path)) throw Error("cannot write '" + path + "': it is a folder");
    if (access(path.c_str(), F_OK) == 0 && access(path.c_str(), W_OK) != 0)
        throw Error("cannot write '" + path + "': " + std::strerror(errno));
}

Flag* output(App& app, const std::string& flag, std::string& target, const std::string& help) {
    const auto set = [&target](const std::string& t) {
        try {
            check_writable(t);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        target = t;
        return std::string();
    };
    return app.value(flag, set, help, "FILE", target);
}

Flag* folder(App& app, const std::string& flag, std::string& target, const std::string& help) {
    const auto set = [&target](const std::string& t) {
        if (!std::filesystem::is_directory(t)) return "expects an existing folder, got '" + t + "'";
        target = t;
        return std::string();
    };
    return app.value(flag, set, help, "DIR", target);
}

bool App::parse(int argc, const char* const* argv) {
    for (int i = 1; i < argc; ++i) {  // --flag=value for a flag that takes none: an error, not a value
        const std::string_view a = argv[i];
        const auto eq = a.find('=');
        if (!a.starts_with("--") || eq == std::string_view::npos) continue;
        const CLI::Option* o = app_->get_option_no_throw(std::string(a.substr(0, eq)));
        if (o != nullptr && o->get_expected_max() == 0)
            throw Error(std::string(a.substr(0, eq)) + " takes no value, got '" + std::string(a) + "'");
    }
    try {
        app_->parse(argc, argv);
        return true;
    } catch (const CLI::CallForHelp&) {
        std::fputs(app_->help().c_str(), stdout);
    } catch (const CLI::CallForAllHelp&) {
        std::fputs(app_->help("", CLI::AppFormatMode::All).c_str(), stdout);
    } catch (const CLI::CallForVersion& v) {
        std::printf("%s\n", v.what());
    } catch (const CLI::ParseError& e) {
        throw Error(std::string(e.what()) + " (see --help)");
    }
    return false;
}

void parse_or_exit(App& app, int argc, const char* const* argv, const std::string& program) {
    try {
        if (app.parse(argc, argv)) return;
    } catch (const Error& e) {
        std::fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
        std::exit(2);
    }
    std::exit(0);
}

}  // namespace glint::cli
