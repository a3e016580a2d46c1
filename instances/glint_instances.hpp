// instances/glint_instances.hpp: the project's own programs (tests, benchmarks, examples) include
// this so that render_named's and render_first_hit_named's instantiations for AnyAccel are not
// compiled again in each of them: they are compiled once, in instances/glint_instances.cpp
// (CMake target glint_instances, linked through glint_build). They hold the path tracer's
// eight policy combinations and the construction of every direct-lighting policy
// (tracer/named_render.hpp), the largest piece of code in every program that renders by name;
// a program passes its accelerator as AnyAccel (any_accel_view, or accelerator_choices()).
// The name tables whose entries construct things (direct_choices, sampler_choices,
// accelerator_choices: the policies and the trees) are compiled here too, so that a program
// listing their names for its command line does not compile every policy and tree again.
// The Python module, always built without -march, shares them where the programs are built
// without -march too (GLINT_NATIVE=OFF) and compiles its own otherwise.
//
// Not part of the library: glint stays header-only, and a user's program instantiates what
// it calls.
#pragma once

#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/first_hit_layers.hpp>
#include <glint/tracer/named_render.hpp>

namespace glint {

extern template RenderResult render_named<float>(const Scene<float>&, const AnyAccel&, const NamedRender<float>&);
extern template std::span<const Choice<DirectChoice<float> (*)(const Scene<float>&, const AnyAccel&, const PathTracerSettings<float>&,
                                                               const RenderSettings&)>>
direct_choices<float>();
extern template std::span<const Choice<AcceleratorChoice (*)(std::span<const TriangleVertices<float>>)>>
accelerator_choices<float>();
extern template std::span<const Choice<SamplerChoice<float> (*)(int, int, std::uint64_t)>> sampler_choices<float>();
extern template FirstHitImages render_first_hit_named<float>(const Scene<float>&, const AnyAccel&,
                                                                       const NamedRender<float>&);

}  // namespace glint
