// Regions of the body with their own physics, read into the Scene after its mesh, zones and
// skeleton: [[material.region]] (tets with their own elastic constants and density) and
// [[muscle]] / [muscles] (each muscle's tets, its fibre field: a constant direction, the Laplace
// field from origin to insertion, or a CSV file per tet; its law, muscle.hpp; and its activation:
// a constant, keyframes in time, or a table of a joint's angle). Keys in docs/scenes.md.
#pragma once
#include <memory>

#include "isochor/models/material.hpp"
#include "isochor/scene/scene.hpp"

namespace isochor {

// Reads [[material.region]] into sc.material.regions. Bad keys throw Error naming the key.
void parse_material_regions(const Section& material, Scene& sc);
// The materials of the regions as the assembly takes them: the body's (index 0) and one per
// region, and each tet's index among them (empty without regions).
struct TetMaterials {
  std::vector<std::shared_ptr<const Material>> materials;
  std::vector<int> material_of;
  std::vector<double> density;  // per tet
};
TetMaterials scene_tet_materials(const Scene& sc);

// Reads [[muscle]] and [muscles] into sc. Bad keys throw Error naming the key and its line.
void parse_muscles(const Section& root, Scene& sc);

// The scene's muscles as the assembly takes them (one entry per tet of the mesh).
FibreField scene_fibre_field(const Scene& sc);

}  // namespace isochor
