// The instantiations that instances/glint_instances.hpp declares extern.
#include "glint_instances.hpp"

namespace glint {

template RenderResult render_named<DefaultAccel, float>(const Scene<float>&, const DefaultAccel&, const NamedRender<float>&);

}  // namespace glint
