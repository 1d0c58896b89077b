// BVH motion-capture files (Biovision hierarchy): the joint tree with its offsets and channels,
// and the motion table (one row of channel values per frame). Angles stay in degrees as written.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

namespace isochor {

struct BvhJoint {
  enum Channel { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };
  std::string name;
  int parent = -1;  // index in Bvh::joints, -1 for the root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::vector<Channel> channels;  // in file order
  int first_channel = 0;          // column of its first channel in Bvh::motion
};

// "Xposition" ... "Zrotation", as BVH files write them.
const char* bvh_channel_name(BvhJoint::Channel c);

struct Bvh {
  std::vector<BvhJoint> joints;  // in file order (parents before children); End Sites are not joints
  double frame_time = 0;         // s
  Eigen::MatrixXd motion;        // frames x channels

  int find(const std::string& name) const;  // -1 if absent
  int channels() const { return static_cast<int>(motion.cols()); }
};

// Reads a BVH file; errors name the file, the line and what was expected.
Bvh read_bvh(const std::string& path);
Bvh parse_bvh(const std::string& text, const std::string& name);

}  // namespace isochor
