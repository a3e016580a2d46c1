// instances/glint_instances.hpp: the project's own programs (tests, benchmarks, examples, the
// Python module aside) include this so that render_named's instantiation for the default
// accelerator is not compiled again in each of them: it is compiled once, in
// instances/glint_instances.cpp (CMake target glint_instances, linked through glint_build). It
// holds the path tracer's eight policy combinations (tracer/named_render.hpp), the largest
// piece of code in every program that renders by name. The Python module compiles its own:
// it is built without -march, which glint_build may add.
//
// Not part of the library: glint stays header-only, and a user's program instantiates what
// it calls.
#pragma once

#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/named_render.hpp>

namespace glint {

extern template RenderResult render_named<DefaultAccel, float>(const Scene<float>&, const DefaultAccel&, const NamedRender<float>&);

}  // namespace glint
