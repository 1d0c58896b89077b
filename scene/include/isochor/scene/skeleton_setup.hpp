// The scene's [skeleton] block read into a Skeleton (models/skeleton.hpp): bones, joints, their
// motions (keyframes, sinusoids or a BVH file's channels) and the mesh nodes bound to each bone.
#pragma once
#include <memory>
#include <vector>

#include "isochor/core/bvh.hpp"
#include "isochor/core/mesh.hpp"
#include "isochor/core/scene_file.hpp"
#include "isochor/models/skeleton.hpp"

namespace isochor {

// Null when the scene has no [skeleton]. `driven_by` marks nodes already driven by [[boundary]]
// (a node may follow one driver only). Bad keys throw Error naming the key and its line.
std::shared_ptr<Skeleton> parse_skeleton(const Section& s, const SceneFile& file, const Mesh& mesh,
                                         const std::vector<int>& driven_by);

// Keys of some of a BVH joint's channels (`channels`: indices into joint.channels, at most 3)
// against time: one cubic key per frame at f * frame_time holding the channels' values in x, y,
// z; rotations unwrapped so that no step between frames exceeds 180 degrees, then times
// `rotation_scale`; positions as the file writes them. A one-frame file gives a constant.
Driver bvh_keyframes(const Bvh& bvh, const BvhJoint& joint, const std::vector<int>& channels, double rotation_scale);

}  // namespace isochor
