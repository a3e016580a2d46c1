// tests/support/counted_visibility.hpp: a visibility policy (occluders/visibility.hpp) that
// counts the tests it passes on, for single-threaded comparisons of how many shadow rays a
// gather traces (a fixture of tests and benchmarks, not part of the library).
#pragma once

#include <cstdint>

#include <glint/core/math.hpp>

namespace glint {

template <class V>
struct CountedVisibility {
    V vis;
    std::uint64_t* count;  // shared by the copies a gather makes: use it on one thread

    template <class P>
    void set_point(const P& x, const P& n) {
        vis.set_point(x, n);
    }
    template <class P>
    bool visible(const P& y) {
        ++*count;
        return vis.visible(y);
    }
};

}  // namespace glint
