// The instantiations that instances/glint_instances.hpp declares extern.
#include "glint_instances.hpp"

namespace glint {

template RenderResult render_named<float>(const Scene<float>&, const AnyAccel&, const NamedRender<float>&);
template std::span<const Choice<DirectChoice<float> (*)(const Scene<float>&, const AnyAccel&, const PathTracerSettings<float>&,
                                                        const RenderSettings&)>>
direct_choices<float>();
template std::span<const Choice<AcceleratorChoice (*)(std::span<const TriangleVertices<float>>)>> accelerator_choices<float>();
template std::span<const Choice<SamplerChoice<float> (*)(int, int, std::uint64_t)>> sampler_choices<float>();
template FirstHitImages render_first_hit_named<float>(const Scene<float>&, const AnyAccel&, const NamedRender<float>&);

}  // namespace glint
