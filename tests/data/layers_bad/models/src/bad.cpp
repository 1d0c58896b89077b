// Physics that reaches up into the scene layer: the include-rule test must name this line.
#include "isochor/models/forces.hpp"
#include "isochor/scene/scene.hpp"
