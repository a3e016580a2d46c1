// The instantiations that instances/glint_instances.hpp declares extern.
#include "glint_instances.hpp"

namespace glint {

template RenderResult render_named<float>(const Scene<float>&, const AnyAccel&, const NamedRender<float>&);
template FirstHitImages render_first_hit_named<float>(const Scene<float>&, const AnyAccel&, const NamedRender<float>&);

}  // namespace glint
