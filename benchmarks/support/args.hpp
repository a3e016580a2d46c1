// benchmarks/support/args.hpp: bench_cones' command-line walk (every other program parses its
// flags through cli/flags.hpp; bench_cones stays here while the open finding in
// docs/hardening.md, its tiles' rays changing with that port, is not explained). Flags
// come one at a time; a flag's value is the next argument, and numbers are parsed whole
// and range checked, so that a bad command line stops, before any long work starts, with
// an Error naming the flag and the text it got (the program's handler adds its own name).
#pragma once

#include <charconv>
#include <limits>
#include <string>
#include <system_error>

#include <glint/core/error.hpp>

namespace glint::bench {

class Args {
public:
    Args(int argc, char** argv) : argc_(argc), argv_(argv) {}

    /// Moves to the next argument; false after the last.
    bool next() {
        if (++i_ >= argc_) return false;
        flag_ = argv_[i_];
        return true;
    }
    /// The argument next() moved to.
    const std::string& flag() const { return flag_; }

    /// The argument after the current flag (consumed).
    std::string value() {
        if (i_ + 1 >= argc_) fail("needs a value");
        return argv_[++i_];
    }
    /// value() parsed as an N, all of its text (for options whose own struct checks the range).
    template <class N>
    N number() {
        return parse<N>(std::numeric_limits<N>::lowest(), std::numeric_limits<N>::max(), "a number");
    }
    /// value() parsed as an N, all of its text, in [lo, hi].
    template <class N>
    N number(N lo, N hi) {
        return parse<N>(lo, hi, "a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }

    /// Throws the error of a flag the program does not know; `usage` lists the ones it does.
    [[noreturn]] void unknown(const std::string& usage) const {
        throw Error("unknown option '" + flag_ + "'" + (usage.empty() ? "" : "\nusage: " + usage));
    }

private:
    template <class N>
    N parse(N lo, N hi, const std::string& what) {
        const std::string v = value();
        N x{};
        const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
        if (ec != std::errc{} || end != v.data() + v.size() || !(x >= lo && x <= hi))
            fail("expects " + what + ", got '" + v + "'");
        return x;
    }
    [[noreturn]] void fail(const std::string& what) const { throw Error(flag_ + " " + what); }

    int argc_, i_ = 0;
    char** argv_;
    std::string flag_;
};

}  // namespace glint::bench
