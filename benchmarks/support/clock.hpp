// benchmarks/support/clock.hpp: wall seconds since a steady_clock time point.
#pragma once

#include <chrono>

namespace glint::bench {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace glint::bench
