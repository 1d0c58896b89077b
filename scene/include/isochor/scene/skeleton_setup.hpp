// The scene's [skeleton] block read into a Skeleton (models/skeleton.hpp): bones, joints, their
// motions (keyframes, sinusoids or a BVH file's channels) and the mesh nodes bound to each bone.
#pragma once
#include <memory>
#include <vector>

#include "isochor/core/mesh.hpp"
#include "isochor/core/scene_file.hpp"
#include "isochor/models/skeleton.hpp"

namespace isochor {

// Null when the scene has no [skeleton]. `driven_by` marks nodes already driven by [[boundary]]
// (a node may follow one driver only). Bad keys throw Error naming the key and its line.
std::shared_ptr<Skeleton> parse_skeleton(const Section& s, const SceneFile& file, const Mesh& mesh,
                                         const std::vector<int>& driven_by);

}  // namespace isochor
