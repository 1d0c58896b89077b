// What the run file records of a scene besides the body (core/output.hpp: SceneRecord): the up
// direction a viewer turns upward and every collider's shape, so that tools read them from the
// file instead of parsing the scene's text.
#include "isochor/scene/body_setup.hpp"
#include "isochor/scene/scene.hpp"

namespace isochor {

namespace {

ColliderRecord collider_record(const Collider& C) {
  using K = ColliderShape::Kind;
  const ColliderShape& S = C.shape;
  ColliderRecord r;
  r.name = C.name;
  r.shape = S.kind == K::plane      ? "plane"
            : S.kind == K::sphere   ? "sphere"
            : S.kind == K::capsule  ? "capsule"
            : S.kind == K::box      ? "box"
            : S.kind == K::cylinder ? "cylinder"
                                    : "mesh";
  switch (S.kind) {
    case K::plane:
      break;
    case K::sphere:
      r.dimensions = {{"radius", S.radius}};
      break;
    case K::capsule:
      r.dimensions = {{"radius", S.radius}, {"length", 2 * S.half_length}};
      break;
    case K::box:
      r.dimensions = {{"size_x", 2 * S.half_extents.x()},
                      {"size_y", 2 * S.half_extents.y()},
                      {"size_z", 2 * S.half_extents.z()},
                      {"rounding", S.rounding}};
      break;
    case K::cylinder:
      r.dimensions = {{"radius", S.radius}, {"length", 2 * S.half_length}, {"wall", S.wall}, {"rounding", S.rounding}};
      break;
    case K::mesh:
      if (S.mesh) {
        r.vertices = S.mesh->vertices();
        r.triangles = S.mesh->triangles();
      }
      break;
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r.rest_pose[3 * i + j] = C.rotation(i, j);
    r.rest_pose[9 + i] = C.center(i);
  }
  return r;
}

}  // namespace

SceneRecord scene_record(const Scene& sc) {
  SceneRecord r;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  r.up_source = "z (no ground, no gravity)";
  if (!sc.colliders.empty() && sc.colliders.front().name == "contact.ground") {
    up = sc.colliders.front().rotation.col(2).normalized();
    r.up_source = "the ground's normal";
  } else if (sc.gravity.norm() > 0) {
    up = -sc.gravity.normalized();
    r.up_source = "against gravity";
  }
  r.up = {up.x(), up.y(), up.z()};
  for (const Collider& C : sc.colliders) r.colliders.push_back(collider_record(C));
  if (sc.skeleton)
    for (const BoneSpec& b : sc.skeleton->bones())
      r.bones.push_back(
          {b.name, b.parent, {b.from.x(), b.from.y(), b.from.z()}, {b.to.x(), b.to.y(), b.to.z()}, b.radius});
  if (!sc.muscles.empty()) {
    const FibreField f = scene_fibre_field(sc);
    for (const Scene::MuscleSpec& m : sc.muscles) r.muscles.push_back(m.name);
    r.tet_muscle = f.muscle_of;
    r.tet_fibre.resize(3, sc.mesh.num_tets());
    for (int e = 0; e < sc.mesh.num_tets(); ++e)
      r.tet_fibre.col(e) = f.muscle_of[e] >= 0 ? f.direction[e] : Eigen::Vector3d::Zero();
  }
  r.render = sc.render;
  return r;
}

void bone_poses(const Scene& sc, double t, std::vector<double>& out) {
  out.clear();
  if (!sc.skeleton) return;
  sc.skeleton->realize(t);
  const std::vector<BoneSpec>& bones = sc.skeleton->bones();
  for (std::size_t b = 0; b < bones.size(); ++b) {
    // The bone's frame: a rest point X, at s = X - origin in it, is at R s + p.
    const Eigen::Matrix3d& R = sc.skeleton->rotation(static_cast<int>(b));
    const Eigen::Vector3d shift = sc.skeleton->position(static_cast<int>(b)) - R * bones[b].origin;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out.push_back(R(i, j));
    for (int i = 0; i < 3; ++i) out.push_back(shift[i]);
  }
}

RunInfo run_info(const Scene& sc, const std::string& command) {
  RunInfo info{sc.file.text_as_run(), sc.file.name(), command, scene_record(sc), sc.file.input_digests(), {}};
  info.input_files.push_back(sc.file.name());
  for (const auto& [name, path] : sc.file.input_files()) info.input_files.push_back(path);
  return info;
}

}  // namespace isochor
