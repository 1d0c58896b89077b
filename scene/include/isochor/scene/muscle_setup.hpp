// The scene's [[muscle]] tables and [muscles] read into Scene::muscles: each muscle's tets (a zone
// or a selection), its fibre field (a constant direction, the Laplace field from origin to
// insertion, or a CSV file per tet), its law (muscle.hpp) and its activation (a constant,
// keyframes in time, or a table of a joint's angle). Keys in docs/scenes.md.
#pragma once
#include "isochor/scene/scene.hpp"

namespace isochor {

// Reads [[muscle]] and [muscles] into sc (after its mesh, zones and skeleton). Bad keys throw
// Error naming the key and its line.
void parse_muscles(const Section& root, Scene& sc);

// The scene's muscles as the assembly takes them (one entry per tet of the mesh).
FibreField scene_fibre_field(const Scene& sc);

}  // namespace isochor
