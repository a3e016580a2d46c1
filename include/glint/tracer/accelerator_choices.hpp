// glint/tracer/accelerator_choices.hpp: the ray accelerators by name ({name, help, make},
// tracer/choice.hpp), for a command line that builds one over a scene's triangles: the default
// 8-wide BVH as its own type (its tracers are instantiated for it directly), any other behind
// one virtual call per ray (AnyAccel), so that all of them share one set of instantiations.
#pragma once

#include <memory>
#include <span>
#include <type_traits>
#include <variant>

#include <glint/core/ray.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/tracer/choice.hpp>
#include <glint/trees/kdtree_builder.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/trees/traversal.hpp>

namespace glint {

/// The default accelerator: the 8-wide BVH with Moller-Trumbore leaves, glint's fastest tree.
using DefaultAccel = MeshBvh<MollerTrumbore<float>, 8>;

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
};

/// A built accelerator: the default BVH as its own type, or any other behind AnyAccel.
using AcceleratorChoice = std::variant<std::unique_ptr<const DefaultAccel>, std::unique_ptr<const AnyAccel>>;

namespace detail {
template <class A>
class AccelModel final : public AnyAccel {
public:
    explicit AccelModel(std::span<const TriangleVertices<float>> tris) : a_(tris) {}
    bool closest_hit(const Ray<float>& ray, StoreHit<float>& hit) const override { return a_.closest_hit(ray, hit); }
    bool any_hit(const Ray<float>& ray) const override { return a_.any_hit(ray); }

private:
    A a_;
};

template <class A>
AcceleratorChoice any_accel(std::span<const TriangleVertices<float>> tris) {
    return std::unique_ptr<const AnyAccel>(std::make_unique<const AccelModel<A>>(tris));
}

template <class A>
AcceleratorChoice default_accel(std::span<const TriangleVertices<float>> tris) {
    return std::make_unique<const A>(tris);
}
}  // namespace detail

/// The table (a template only so that a file including this header builds no tree it does not
/// name; the trees are float-only).
template <Scalar T = float>
std::span<const Choice<AcceleratorChoice (*)(std::span<const TriangleVertices<float>>)>> accelerator_choices() {
    static_assert(std::is_same_v<T, float>, "glint::accelerator_choices: the trees here are float-only");
    static constexpr Choice<AcceleratorChoice (*)(std::span<const TriangleVertices<float>>)> table[] = {
        {"bvh8", "8-wide BVH, the fastest", detail::default_accel<DefaultAccel>},
        {"bvh4", "4-wide BVH", detail::any_accel<MeshBvh<MollerTrumbore<float>, 4>>},
        {"kd-compact", "kd-tree in Szecsi 2009 4.4's compact-subtree layout",
         detail::any_accel<KdTree<float, MollerTrumbore<float>, CompactSubtrees<15>>>},
        {"bvh8-virtual", "bvh8 behind a virtual call (what the call costs)", detail::any_accel<DefaultAccel>},
    };
    return table;
}

}  // namespace glint
