// benchmarks/support/clock.hpp: wall seconds since a steady_clock time point; the clock of
// bench_trees --user-meshes' passes (wall time, or the thread's CPU time).
#pragma once

#include <chrono>
#include <cstdint>
#include <ctime>

namespace glint::bench {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// A std::chrono clock for timed passes: steady wall time, or with `thread_cpu` set (the
/// programs' --cpu-time) the calling thread's CPU time, which leaves out the time other
/// processes take from the core on a busy shared machine.
struct PassClock {
    using duration = std::chrono::nanoseconds;  ///< Nanoseconds.
    using rep = duration::rep;                  ///< Tick count type.
    using period = duration::period;            ///< One nanosecond.
    using time_point = std::chrono::time_point<PassClock>;  ///< A reading.
    static constexpr bool is_steady = true;  ///< Never goes back.
    static inline bool thread_cpu = false;  ///< Time by the thread's CPU clock (--cpu-time).
    /// The current reading of the chosen clock.
    static time_point now() noexcept {
        if (!thread_cpu)
            return time_point(std::chrono::duration_cast<duration>(std::chrono::steady_clock::now().time_since_epoch()));
        timespec ts{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
        return time_point(duration(std::int64_t(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec));
    }
};

}  // namespace glint::bench
