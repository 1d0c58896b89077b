// One HDF5 file per run (schema in docs/output.md) and an XDMF sidecar that ParaView opens as a
// time series. Frames are flushed as they are written: a killed run keeps every finished frame.
#pragma once
#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "isochor/core/embedding.hpp"
#include "isochor/core/mesh.hpp"

namespace isochor {

// A collider as the run file records it under /colliders (docs/output.md), so that tools draw
// it without parsing the scene: its shape and dimensions, its rest pose, and a mesh collider's
// surface. Where it is at each frame is /frames/collider_pose.
struct ColliderRecord {
  std::string name;                                        // "contact.ground", "contact.plane[0]", "collider[2]"
  std::string shape;                                       // plane, sphere, capsule, box, cylinder, mesh
  std::vector<std::pair<std::string, double>> dimensions;  // m: radius, length, size_x, ..., wall
  std::array<double, 12> rest_pose{1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};  // A (row-major), b: x = A l + b
  Points vertices;  // mesh: its surface in the collider's frame (scaled)
  std::vector<Tri> triangles;
};

// A bone of the scene's skeleton as the run file records it under /bones (docs/output.md): its
// name, its parent (-1: none) and its capsule in the rest pose (world coordinates). Where it is
// at each frame is /frames/bone_pose: A, b with a rest point X at A X + b.
struct BoneRecord {
  std::string name;
  int parent = -1;
  std::array<double, 3> from{0, 0, 0}, to{0, 0, 0};
  double radius = 0;
};

// What a viewer needs besides the body: the scene's up direction, its colliders and bones.
struct SceneRecord {
  std::array<double, 3> up{0, 0, 1};      // unit
  std::string up_source;                  // why that is up ("the ground's normal", "against gravity", ...)
  std::vector<ColliderRecord> colliders;  // the scene's order: the ground, the planes, the [[collider]]s
  std::vector<BoneRecord> bones;          // the [skeleton]'s bones, in its order
  // Muscles (/muscles): their names (the columns of /frames/activation), each tet's muscle (-1:
  // none) and rest fibre direction (3 x tets); empty without muscles.
  std::vector<std::string> muscles;
  std::vector<int> tet_muscle;
  Points tet_fibre;
  // An artist's mesh carried by the tets (/render); null without one.
  std::shared_ptr<const RenderMesh> render;
};

// Named sets of tets: /zones, and the columns of /frames/volume after "total".
using Zones = std::vector<std::pair<std::string, std::vector<int>>>;

struct RunInfo {
  std::string scene_text;  // the scene as run
  std::string scene_file;  // where it came from
  std::string command;     // e.g. "run", "mesh"
  SceneRecord scene;       // written as /colliders and the root attributes up, up_source
  std::string inputs;      // SceneFile::input_digests(): a resume refuses a changed input file
  // The files the scene read (the scene file first): the output must not be one of them.
  std::vector<std::string> input_files;
};

struct Frame {
  double time = 0.0;
  const Points* positions = nullptr;                 // all nodes
  const Points* velocities = nullptr;                // all nodes (m/s): with the positions, what a resume needs
  const std::vector<double>* multipliers = nullptr;  // the constraints' multipliers (a resume's start)
  std::vector<double> volumes;                       // total, then each zone (in the order given at open)
  std::array<double, 3> energy{0, 0, 0};             // kinetic, elastic, external potential
  const std::vector<double>* pressure = nullptr;     // per tet, when pressure output is on
  const Points* loads = nullptr;                     // the applied load on every node (N), when the scene has loads
  const Points* contact = nullptr;  // the colliders' force on every node (N), when the scene has colliders
  // Where each collider is: 12 numbers per collider, its local-to-world rotation A (row-major)
  // and translation b (x = A l + b), in the scene's order (the ground and planes first).
  const std::vector<double>* collider_poses = nullptr;
  // Each collider's factor on its radius (Collider::resize; 1: its own), in the same order.
  const std::vector<double>* collider_scales = nullptr;
  // Where each bone is: 12 numbers per bone, A (row-major) and b with a rest point X at A X + b,
  // in the order of SceneRecord::bones.
  const std::vector<double>* bone_poses = nullptr;
  // Each muscle's activation (0..1), in the order of SceneRecord::muscles.
  const std::vector<double>* activations = nullptr;
  std::vector<std::pair<std::string, double>> stats;  // per-frame series under /stats
};

// Where a resumed run continues: its last complete frame, read back from the file.
struct ResumePoint {
  int frame = -1;  // index of the last complete frame (frames after it were dropped)
  double time = 0;
  Points positions, velocities;         // every node
  std::vector<double> multipliers;      // the constraints' (empty if none were written)
  std::map<std::string, double> stats;  // the per-frame /stats series at that frame
  std::string status;                   // what the file said before: running, failed, ...
};

class OutputWriter {
 public:
  enum class Mode {
    create,     // a new file; an existing one (or its sidecar) is an error
    overwrite,  // a new file, replacing what is there
    resume,     // continue the file: it must have been written from the same scene
  };
  // `zones` are written under /zones and name the columns of /frames/volume. The file is locked
  // for the writer's life (a second writer on the same path fails at start).
  OutputWriter(const std::string& path, const Mesh& mesh, const Zones& zones, const RunInfo& info, bool pressure,
               Mode mode = Mode::create);
  ~OutputWriter();
  OutputWriter(const OutputWriter&) = delete;
  OutputWriter& operator=(const OutputWriter&) = delete;

  void write_frame(const Frame& f);
  // Attributes on /stats (run totals).
  void set_stat(const std::string& name, double value);
  void set_stat(const std::string& name, const std::string& value);
  // The root attribute `status`: "running" while written, then "finished", "interrupted" or
  // "failed" (docs/output.md).
  void set_status(const std::string& status);
  // Mode::resume: the frame the run continues from. Opening for resume reads only; the file is
  // changed by continue_run(), once the run has accepted the resume (status "running", the frames
  // after resume_point() cut, the last stop's reasons removed).
  const ResumePoint& resume_point() const;
  void continue_run();
  // Closes the file (also done by the destructor).
  void close();
  // Closes and removes the file and its sidecar: a new output that failed before its first frame
  // leaves nothing behind (not for Mode::resume, whose file holds an earlier run's frames).
  void discard();

  int frames_written() const;
  const std::string& path() const;
  std::string xdmf_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Bytes free for an output at `path` (on the file system of its nearest existing directory), and
// within the file size limit (ulimit -f); infinity where unknown.
double output_room_bytes(const std::string& path);

// Whether a process holds the writer's lock on this file (a run still writing it).
bool output_is_being_written(const std::string& path);

// To be called first in a program that writes run files: HDF5's own clean-up at exit is not
// registered. A file whose flush failed (a full disk, a size limit) stays half-closed in HDF5's
// tables, and its clean-up at exit then crashes (HDF5 1.10's H5F__close_cb); every file isochor
// writes is flushed and closed by its writer, so nothing is lost without it.
void hdf5_no_cleanup_at_exit();

// The version and git revision compiled into this build.
const char* isochor_version();
const char* isochor_git_revision();

}  // namespace isochor
