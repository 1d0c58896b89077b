// The scene's [character] block: a rigged glTF character (core/gltf.hpp) made into a simulation.
// Its render mesh is alpha-wrapped (any triangle soup) and the wrap filled with tets by Gmsh; each
// joint becomes a bone in prescribed motion (the clip, or the rest pose held) whose capsule, from
// the joint to its children, binds the nodes within reach; each tet takes the region of the joint
// that dominates the skin weights nearest it (mesh zones, [zones] from_mesh); the render mesh is
// embedded in the tets and carried to the run file (/render).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "isochor/core/embedding.hpp"
#include "isochor/core/mesh.hpp"
#include "isochor/core/scene_file.hpp"
#include "isochor/models/skeleton.hpp"

namespace isochor {

struct Character {
  Mesh mesh;                    // zones: the regions (one per joint, or character.regions)
  std::vector<BoneSpec> bones;  // one per joint, parents first, nodes bound
  std::shared_ptr<RenderMesh> render;
};

// `duration`: the run's length (s), over which a looped clip repeats. Bad keys and files throw
// Error naming the key or file. `filled`: the simulation mesh (nodes and tets) an earlier run of
// this scene filled, used instead of wrapping and filling again: Gmsh's fill of the wrap varies
// with the thread count, and a resumed run must go on with the mesh it started on.
Character parse_character(const Section& s, const SceneFile& file, double duration, const Mesh* filled = nullptr);

}  // namespace isochor
