// cli/flags.cpp: cli/flags.hpp's App: the flags, the command line's parse and --help.
#include "flags.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <utility>

#include <unistd.h>

#include <glint/core/error.hpp>

namespace glint::cli {

App::App(const std::string& description) : description_(description) {}

App::~App() = default;

void App::version(const std::string& text) { version_ = text; }

Flag* App::value(const std::string& flag, std::function<std::string(const std::string&)> set, const std::string& help,
                 const std::string& type, const std::string& default_text, bool repeat) {
    auto f = std::make_unique<Flag>();
    f->name_ = flag, f->help_ = help, f->type_ = type, f->default_ = default_text;
    f->set_ = std::move(set);
    f->repeat_ = repeat;
    flags_.push_back(std::move(f));
    return flags_.back().get();
}

Flag* App::flag(const std::string& flag, std::function<void()> set, const std::string& help) {
    auto f = std::make_unique<Flag>();
    f->name_ = flag, f->help_ = help;
    f->set_flag_ = std::move(set);
    flags_.push_back(std::move(f));
    return flags_.back().get();
}

Flag* App::find(std::string_view name) {
    for (const auto& f : flags_)
        if (f->name_ == name) return f.get();
    return nullptr;
}

namespace {
/// One --help line: the flag, its type and default in a column of 30, then its help, whose
/// further lines are indented to that column.
void help_line(std::string& out, const std::string& left, const std::string& help) {
    std::string line = "  " + left;
    line += line.size() < 30 ? std::string(30 - line.size(), ' ') : "\n" + std::string(30, ' ');
    for (const char c : help) {
        line += c;
        if (c == '\n') line += std::string(30, ' ');
    }
    out += line + "\n";
}
}  // namespace

std::string App::help(const std::string& program) const {
    std::string out = description_ + "\nUsage: " + program + " [OPTIONS]\n\nOptions:\n";
    help_line(out, "-h,--help", "Print this help message and exit");
    if (!version_.empty()) help_line(out, "--version", "Display program version information and exit");
    std::vector<std::string> groups{""};
    for (const auto& f : flags_)
        if (std::find(groups.begin(), groups.end(), f->group_) == groups.end()) groups.push_back(f->group_);
    for (const std::string& g : groups) {
        if (!g.empty()) out += "\n\n" + g + ":\n";
        for (const auto& f : flags_) {
            if (f->group_ != g) continue;
            std::string left = f->name_;
            if (f->set_) left += " " + f->type_ + (f->default_.empty() ? "" : "=" + f->default_);
            help_line(out, left, f->help_);
        }
    }
    return out;
}

bool App::parse(int argc, const char* const* argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        if (a == "-h" || a == "--help") {
            std::fputs(help(argv[0]).c_str(), stdout);
            return false;
        }
        if (a == "--version" && !version_.empty()) {
            std::printf("%s\n", version_.c_str());
            return false;
        }
    }
    for (int i = 1; i < argc; ++i) {  // every value stored first, then handed over in flag order
        const std::string_view a = argv[i];
        const auto eq = a.find('=');
        Flag* f = a.starts_with("--") ? find(a.substr(0, eq)) : nullptr;
        if (f == nullptr)
            throw Error("unexpected argument '" + std::string(a) + (a.starts_with("--") ? "': no such flag" : "'") + " (see --help)");
        if (!f->set_) {
            if (eq != std::string_view::npos) throw Error(f->name_ + " takes no value, got '" + std::string(a) + "'");
            f->values_.assign(1, "");
            continue;
        }
        std::string v;
        if (eq != std::string_view::npos) {
            v = a.substr(eq + 1);
        } else if (i + 1 < argc && !std::string_view(argv[i + 1]).starts_with("--")) {
            v = argv[++i];
        } else {
            throw Error(f->name_ + ": expects a value (" + f->type_ + ") (see --help)");
        }
        if (!f->repeat_) f->values_.clear();
        f->values_.push_back(std::move(v));
    }
    for (const auto& f : flags_) {
        for (const std::string& v : f->values_) {
            if (!f->set_) {
                f->set_flag_();
                continue;
            }
            if (const std::string error = f->set_(v); !error.empty()) throw Error(f->name_ + ": " + error + " (see --help)");
        }
    }
    return true;
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
