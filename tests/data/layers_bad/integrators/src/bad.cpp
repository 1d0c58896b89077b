// An integrator that sees meshes, and a header by its bare name.
#include "isochor/core/mesh.hpp"
#include "isochor/mesh.hpp"
