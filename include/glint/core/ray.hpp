// glint/core/ray.hpp: a ray with its valid parameter interval.
#pragma once

#include <glint/core/math.hpp>

namespace glint {

/// Points o + t d for t in the open interval (tmin, tmax). The direction need not be
/// normalized; t is measured in units of |d|.
template <class T>
struct Ray {
    Vec3<T> origin{0};
    Vec3<T> direction{0, 0, 1};
    T tmin = T(0);
    T tmax = infinity<T>;

    Vec3<T> at(T t) const { return origin + direction * t; }
};

}  // namespace glint
