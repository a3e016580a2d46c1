// instances/glint_instances.hpp: the project's own programs (tests, benchmarks, examples) include
// this so that render_named's instantiation for the default accelerator is not compiled again
// in each of them: it is compiled once, in instances/glint_instances.cpp (CMake target
// glint_instances, linked through glint_build). It holds the path tracer's eight policy
// combinations (tracer/named_render.hpp), the largest piece of code in every program that
// renders by name. The Python module, always built without -march, shares it where the
// programs are built without -march too (GLINT_NATIVE=OFF) and compiles its own otherwise.
//
// Not part of the library: glint stays header-only, and a user's program instantiates what
// it calls.
#pragma once

#include <glint/tracer/accelerator_choices.hpp>
#include <glint/tracer/named_render.hpp>

namespace glint {

extern template RenderResult render_named<DefaultAccel, float>(const Scene<float>&, const DefaultAccel&, const NamedRender<float>&);

}  // namespace glint
