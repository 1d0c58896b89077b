// The [zones] table read into the Scene's zones, and the choice made for the user: CNH with no
// zone named gets patches the size of a 2-ring (kDefaultPatchRings), the smallest patches whose
// inf-sup constant stays bounded under refinement (docs/results/infsup); the paper's global zone
// is `zones.global = true`. Keys in docs/scenes.md.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "isochor/models/infsup.hpp"
#include "isochor/scene/scene.hpp"

namespace isochor {

constexpr int kDefaultPatchRings = 2;

struct ZoneChoice {
  std::vector<std::pair<std::string, std::vector<int>>> zones;  // name, sorted tets
  // zones[0, generated) are global, rings and patches (not named by the user), the patches
  // zones[patches_begin, generated).
  std::size_t patches_begin = 0, generated = 0;
  int patch_rings = 0;     // zones.patches (or the default), 0 without patches
  bool automatic = false;  // the default choice (no zone named in [zones])
};

// Reads [zones] (bad keys throw Error naming the key); cnh: the model keeps zones by default.
ZoneChoice parse_zones(const Section& zones, const Mesh& mesh, const SceneFile& file, bool cnh);

// Once the driven nodes are known (boundaries, bones): a generated zone whose every tet has its
// four nodes driven is dropped (no free dof moves its volume: its constraint row would be zero);
// a named one stops with one line naming it. Patches too coarse for the body (fewer than two
// across one of its principal directions) add a note to sc.notes. Sets sc.zones.
void settle_zones(const Section& zones, ZoneChoice choice, Scene& sc);

// How many zones span the body along each of its principal directions (the body's extent over
// the zones' mean extent along it), thinnest direction first, with the body's extents.
struct ZonesAcross {
  Eigen::Vector3d across = Eigen::Vector3d::Zero();
  Eigen::Vector3d extent = Eigen::Vector3d::Zero();
};
ZonesAcross zones_across(const Mesh& mesh, const std::vector<std::pair<std::string, std::vector<int>>>& zones);

// The inf-sup constant of the scene's zones (models/infsup.hpp) against its free dofs: nodes
// driven by boundaries or bones held, rollers held along their directions (`isochor infsup`).
InfSup zones_infsup(const Scene& sc);

}  // namespace isochor
