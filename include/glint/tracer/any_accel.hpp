// glint/tracer/any_accel.hpp: AnyAccel, any ray accelerator behind one virtual call per ray
// (or per stream of rays), the accelerator type render_named() (tracer/named_render.hpp) and
// the other integrators chosen by name take, so that their instantiations do not multiply
// with the trees'.
//
// That call costs 0.3% of a path-traced Cornell box's instructions (callgrind, 48 x 48 pixels,
// 4 spp, the 8-wide BVH called directly against the same BVH behind AnyAccel: the same rays,
// about 7 instructions more per ray of some 2000), below the timing noise of paired runs:
// the accelerator is a run-time value there, not a type. A program that wants the tree's own
// type in its inner loop instantiates PathTracer (tracer/path_tracer.hpp) for it.
//
//   const MeshBvh<MollerTrumbore<float>, 8> bvh(scene.triangles);
//   const RenderResult r = render_named(scene, any_accel_view(bvh), options);
#pragma once

#include <cstddef>
#include <span>
#include <type_traits>
#include <utility>

#include <glint/core/ray.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// Any accelerator behind a virtual call per ray (a RayAccelerator).
class AnyAccel {
public:
    /// The accelerators behind AnyAccel all trace float rays.
    using scalar_type = float;
    virtual ~AnyAccel() = default;
    /// The closest hit in (ray.tmin, ray.tmax), stored in `hit`; false on a miss.
    /// Thread-safe: the tree is read-only.
    virtual bool closest_hit(const Ray<float>& ray, StoreHit<float>& hit) const = 0;
    /// Whether anything lies in (ray.tmin, ray.tmax): the shadow-ray query, which may stop at
    /// the first hit found.
    virtual bool any_hit(const Ray<float>& ray) const = 0;
    /// Closest hits of a stream of rays (trees/tree.hpp's closest_hits(): the held
    /// accelerator's packets where it has them); one virtual call per stream.
    virtual std::size_t closest_hit(std::span<const Ray<float>> rays, std::span<StoreHit<float>> hits) const = 0;
    /// Any hits of a stream of rays (any_hits()), one virtual call per stream.
    virtual std::size_t any_hit(std::span<const Ray<float>> rays, std::span<bool> occluded) const = 0;
};

/// `Held` (an accelerator, or a reference to one) behind AnyAccel.
template <class Held>
class AnyAccelOf final : public AnyAccel {
public:
    /// Constructs the held accelerator (or binds the reference) from `args`.
    template <class... Args>
    explicit AnyAccelOf(Args&&... args) : a_(std::forward<Args>(args)...) {}
    bool closest_hit(const Ray<float>& ray, StoreHit<float>& hit) const override { return a_.closest_hit(ray, hit); }
    bool any_hit(const Ray<float>& ray) const override { return a_.any_hit(ray); }
    std::size_t closest_hit(std::span<const Ray<float>> rays, std::span<StoreHit<float>> hits) const override {
        return closest_hits(a_, rays, hits);
    }
    std::size_t any_hit(std::span<const Ray<float>> rays, std::span<bool> occluded) const override {
        return any_hits(a_, rays, occluded);
    }

private:
    Held a_;
};

/// `accel` behind AnyAccel, by reference (it must outlive the result), e.g. for render_named().
template <RayAccelerator A>
AnyAccelOf<const A&> any_accel_view(const A& accel) {
    static_assert(std::is_same_v<typename A::scalar_type, float>, "glint::any_accel_view: AnyAccel traces float rays");
    return AnyAccelOf<const A&>(accel);
}

}  // namespace glint
