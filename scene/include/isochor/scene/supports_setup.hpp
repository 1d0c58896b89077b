// The component supports (models/supports.hpp) of a scene's [[boundary]] drivers.
#pragma once
#include <memory>

#include "isochor/models/supports.hpp"
#include "isochor/scene/scene.hpp"

namespace isochor {

// The supports of the drivers that hold some components (null if none), over `dofs`. Throws an
// Error naming the drivers if a node's held directions are not independent, or if a held node is
// not one of the model's unknowns (the mass-spring model's interior).
std::unique_ptr<ComponentSupports> make_supports(const Scene& scene, const DofMap& dofs);

}  // namespace isochor
