// glint/core/ray.hpp: a ray with its valid parameter interval.
#pragma once

#include <glint/core/math.hpp>

namespace glint {

/// Points o + t d for t in the open interval (tmin, tmax). The direction need not be
/// normalized; t is measured in units of |d|.
template <class T>
struct Ray {
    /// Point the ray starts from (world space unless the caller says otherwise).
    Vec3<T> origin{0};
    /// Direction d, not necessarily unit length; defaults to +z.
    Vec3<T> direction{0, 0, 1};
    /// Lower end of the open parameter interval; a positive value skips self-intersection near
    /// the origin.
    T tmin = T(0);
    /// Upper end of the open parameter interval; infinite by default, lowered to the closest hit
    /// so far by intersectors.
    T tmax = infinity<T>;

    /// The point origin + t * direction.
    Vec3<T> at(T t) const { return origin + direction * t; }
};

}  // namespace glint
