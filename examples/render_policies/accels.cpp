// render_policies/accels.cpp: the accelerators --accel names besides the default, behind
// AnyAccel (render_options.hpp).
#include <glint/core/error.hpp>
#include <glint/trees/kdtree_builder.hpp>
#include <glint/trees/layouts.hpp>
#include <glint/trees/traversal.hpp>

#include "render_options.hpp"

namespace glint_cli {

namespace {

template <class A>
class AccelModel final : public AnyAccel {
public:
    explicit AccelModel(std::span<const TriangleVertices<float>> tris) : a_(tris) {}
    bool closest_hit(const Ray<float>& ray, StoreHit<float>& hit) const override { return a_.closest_hit(ray, hit); }
    bool any_hit(const Ray<float>& ray) const override { return a_.any_hit(ray); }

private:
    A a_;
};

}  // namespace

const std::vector<std::string>& accel_names() {
    static const std::vector<std::string> v{"bvh8", "bvh4", "kd-compact", "bvh8-virtual"};
    return v;
}

std::unique_ptr<AnyAccel> make_accel(const std::string& name, std::span<const TriangleVertices<float>> tris) {
    // bvh4: the 4-wide BVH; kd-compact: the SAH kd-tree in 000's compact-subtree layout
    // (section 4.4) with Moller-Trumbore leaves; bvh8-virtual: the default tree behind the
    // virtual call, to measure what the call costs.
    if (name == "bvh4") return std::make_unique<AccelModel<MeshBvh<MollerTrumbore<float>, 4>>>(tris);
    if (name == "kd-compact")
        return std::make_unique<AccelModel<KdTree<float, MollerTrumbore<float>, CompactSubtrees<15>>>>(tris);
    if (name == "bvh8-virtual") return std::make_unique<AccelModel<RenderAccel>>(tris);
    std::string names;
    for (const auto& n : accel_names()) names += (names.empty() ? "" : ", ") + n;
    throw Error("unknown accelerator '" + name + "' (" + names + ")");
}

}  // namespace glint_cli
