// glint/tracer/accelerator_choices.hpp: the ray accelerators by name ({name, help, make},
// tracer/choice.hpp), for a command line that builds one over a scene's triangles: each
// built and owned behind AnyAccel (tracer/any_accel.hpp), the accelerator type that
// render_named() takes.
#pragma once

#include <memory>
#include <span>
#include <type_traits>

#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/triangle.hpp>
#include <glint/tracer/any_accel.hpp>
#include <glint/tracer/choice.hpp>
#include <glint/trees/kdtree_builder.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/mesh_bvh.hpp>
#include <glint/trees/traversal.hpp>

namespace glint {

/// The default accelerator: the 8-wide BVH with Moller-Trumbore leaves, glint's fastest tree.
using DefaultAccel = MeshBvh<MollerTrumbore<float>, 8>;

/// A built accelerator, owned.
using AcceleratorChoice = std::unique_ptr<const AnyAccel>;

namespace detail {
template <class A>
AcceleratorChoice any_accel(std::span<const TriangleVertices<float>> tris) {
    return std::make_unique<const AnyAccelOf<A>>(tris);
}
}  // namespace detail

/// The table (a template only so that a file including this header builds no tree it does not
/// name; the trees are float-only).
template <Scalar T = float>
std::span<const Choice<AcceleratorChoice (*)(std::span<const TriangleVertices<float>>)>> accelerator_choices() {
    static_assert(std::is_same_v<T, float>, "glint::accelerator_choices: the trees here are float-only");
    static constexpr Choice<AcceleratorChoice (*)(std::span<const TriangleVertices<float>>)> table[] = {
        {"bvh8", "8-wide BVH, the fastest", detail::any_accel<DefaultAccel>},
        {"bvh4", "4-wide BVH", detail::any_accel<MeshBvh<MollerTrumbore<float>, 4>>},
        {"kd-compact", "kd-tree in Szecsi 2009 4.4's compact-subtree layout",
         detail::any_accel<KdTree<float, MollerTrumbore<float>, CompactSubtrees<15>>>},
    };
    return table;
}

}  // namespace glint
