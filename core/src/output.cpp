#include "isochor/core/output.hpp"
#include "isochor/core/input_file.hpp"

#include <hdf5.h>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "file_room.hpp"
#include "hdf5_util.hpp"
#include "xdmf_sidecar.hpp"
#include "isochor/base/error.hpp"

#ifndef ISOCHOR_VERSION
#define ISOCHOR_VERSION "0.0.0"
#endif
#include "isochor_git_revision.hpp"  // generated at build time (cmake/git_revision.cmake)

namespace isochor {

const char* isochor_version() { return ISOCHOR_VERSION; }
const char* isochor_git_revision() { return ISOCHOR_GIT_REVISION; }

using namespace h5;

namespace {

// The first line where two texts differ (1-based), for the resume check's message.
int first_difference(const std::string& a, const std::string& b) {
  std::istringstream x(a), y(b);
  std::string la, lb;
  for (int line = 1;; ++line) {
    const bool ga = static_cast<bool>(std::getline(x, la)), gb = static_cast<bool>(std::getline(y, lb));
    if (!ga && !gb) return 0;
    if (ga != gb || la != lb) return line;
  }
}

}  // namespace

struct OutputWriter::Impl {
  std::string path, h5_name;
  H file;
  int nodes = 0, tets = 0, frames = 0;
  bool pressure = false;
  bool zone_index = false;  // /mesh/zone exists (a cell attribute "zone" in the sidecar)
  std::unique_ptr<Series> time, positions, velocities, multipliers, volume, energy, pressure_series, collider_pose,
      collider_scale, bone_pose, activation;
  // Per-node vectors of a frame, when the scene has them: "load" and "contact" (kNodeVectors).
  std::map<std::string, std::unique_ptr<Series>> node_series;
  std::map<std::string, std::unique_ptr<Series>> stats;
  H frames_group, xdmf_group, stats_group;
  int lock_fd = -1;
  bool existed = false;          // the path existed before the writer (a failed create leaves it)
  std::size_t resume_zones = 0;  // Mode::resume: the zones, for continue_run
  bool resume_pending = false;   // opened for resume, not yet continued: close() writes nothing
  double frame_bytes = 0;        // what a frame adds to the file: an estimate, then the largest measured
  off_t file_size = 0;           // after the last flush
  ResumePoint resume;

  void lock_path(Mode mode, const RunInfo& info);
  void write_header(const RunInfo& info);
  void write_mesh(const Mesh& mesh, const Zones& zones);
  void write_colliders(const std::vector<ColliderRecord>& colliders);
  void write_bones(const std::vector<BoneRecord>& bones);
  void write_muscles(const SceneRecord& scene);
  void write_render(const SceneRecord& scene);
  // A per-frame row series that the first frame may start (collider poses and scales,
  // activations): appended at frame k, its row `row` numbers.
  void append_optional(std::unique_ptr<Series>& series, const char* name, const std::vector<double>& values,
                       std::vector<hsize_t> row, hsize_t k);
  void create_series(const Zones& zones);

  // Every per-frame series of the file.
  std::vector<Series*> all_series() {
    std::vector<Series*> all{time.get(),           positions.get(), velocities.get(),      multipliers.get(),
                             volume.get(),         energy.get(),    pressure_series.get(), collider_pose.get(),
                             collider_scale.get(), bone_pose.get(), activation.get()};
    for (auto& [name, series] : node_series) all.push_back(series.get());
    for (auto& [name, series] : stats) all.push_back(series.get());
    all.erase(std::remove(all.begin(), all.end(), nullptr), all.end());
    return all;
  }

  // Frames k, k+1, ... removed: the series cut to k rows and their XDMF views unlinked.
  void cut_frames(int k) {
    for (Series* series : all_series())
      if (series->rows() > static_cast<hsize_t>(k)) series->truncate(static_cast<hsize_t>(k));
    for (int j = k;; ++j) {
      bool any = false;
      for (const char* prefix : {"position_", "pressure_", "load_", "contact_"}) {
        const std::string name = prefix + frame_name(j);
        if (H5Lexists(xdmf_group, name.c_str(), H5P_DEFAULT) > 0) {
          check(H5Ldelete(xdmf_group, name.c_str(), H5P_DEFAULT), "unlink " + name);
          any = true;
        }
      }
      if (!any) break;
    }
  }

  // Room for one more frame on the file system and under the file size limit (ulimit -f), with a
  // margin for the metadata written at close; checked before a frame is started, so that a full
  // disk stops the run with every frame before it intact.
  void ensure_room(int k) {
    const double need = 2 * frame_bytes + 256 * 1024;
    const std::string kept = k > 0 ? "frames 0-" + std::to_string(k - 1) + " are intact" : "no frame was written";
    const double avail = free_bytes(path), limit = file_size_limit();
    if (avail < need)
      throw Error(path + ": the disk is full (" + kb(avail) + " free, frame " + std::to_string(k) + " needs about " +
                  kb(need) + "); " + kept);
    if (static_cast<double>(file_size) + need > limit)
      throw Error(path + ": the file size limit (ulimit -f: " + kb(limit) + ") is reached at frame " +
                  std::to_string(k) + "; " + kept);
  }

  void append_frame(const Frame& f, hsize_t k);

  // A frame's bytes before any is measured (positions, velocities, loads, pressures, the scalars
  // and their per-frame views), and the file's size now.
  void start_measuring(std::size_t zones) {
    struct stat st {};
    if (lock_fd >= 0 && ::fstat(lock_fd, &st) == 0) file_size = st.st_size;
    frame_bytes = 8.0 * (9.0 * nodes + (pressure ? tets : 0) + static_cast<double>(zones) + 32) + 4096;
  }

  void measure_growth() {
    struct stat st {};
    if (lock_fd >= 0 && ::fstat(lock_fd, &st) == 0) {
      frame_bytes = std::max(frame_bytes, static_cast<double>(st.st_size - file_size));
      file_size = st.st_size;
    }
  }

  void add_frame_view(const std::string& source, int k, hsize_t width, const std::string& prefix) {
    // /frames/xdmf/<prefix>_<k>: a (rows, width) virtual dataset over frame k of `source`, so
    // that XDMF readers can reference each frame directly without a copy.
    const hsize_t rows = static_cast<hsize_t>(prefix == "pressure" ? tets : nodes);
    std::vector<hsize_t> vdims{rows};
    if (width) vdims.push_back(width);
    H vspace(H5Screate_simple(static_cast<int>(vdims.size()), vdims.data(), nullptr), H5Sclose);
    std::vector<hsize_t> sdims{static_cast<hsize_t>(k + 1), rows}, start{static_cast<hsize_t>(k), 0}, count{1, rows};
    if (width) {
      sdims.push_back(width);
      start.push_back(0);
      count.push_back(width);
    }
    H sspace(H5Screate_simple(static_cast<int>(sdims.size()), sdims.data(), nullptr), H5Sclose);
    check(H5Sselect_hyperslab(sspace, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr), "select");
    H dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    check(H5Pset_virtual(dcpl, vspace, ".", source.c_str(), sspace), "virtual dataset");
    const std::string name = prefix + "_" + frame_name(k);
    H ds(checked(H5Dcreate2(xdmf_group, name.c_str(), H5T_NATIVE_DOUBLE, vspace, H5P_DEFAULT, dcpl, H5P_DEFAULT),
                 "create " + name),
         H5Dclose);
  }

  // The sidecar (xdmf_sidecar.hpp), written as the frames are.
  XdmfSidecar sidecar;
  XdmfLayout layout() const {
    XdmfLayout l{h5_name, nodes, tets, {}, zone_index, pressure};
    for (const auto& [name, series] : node_series) l.node_vectors.push_back(name);
    return l;
  }
  void start_xdmf(const std::vector<double>& times = {}) { sidecar.start(xdmf_file(), layout(), times); }
  void append_xdmf(int k, double time) {
    if (!sidecar.is_open()) start_xdmf();
    sidecar.append(layout(), k, time);
  }
  void close_xdmf() { sidecar.close(); }
  ~Impl() {
    close_xdmf();
    if (lock_fd >= 0) ::close(lock_fd);
  }

  std::string xdmf_file() const { return std::filesystem::path(path).replace_extension(".xdmf").string(); }

  // The scene's input files as the run read them against now (files written before inputs were
  // recorded have none, and are not checked).
  void check_inputs(const std::string& then, const std::string& now) const {
    if (then.empty() || then == now) return;
    std::istringstream a(then), b(now);
    std::string x, y;
    while (std::getline(a, x)) {
      const bool more = static_cast<bool>(std::getline(b, y));
      if (more && x == y) continue;
      const std::string name = x.substr(0, x.find('\t'));
      throw Error(path + ": the scene's input " + name +
                  (more && y.rfind(name + "\t", 0) == 0 ? " changed" : " is not the one it read") +
                  " since the run was written (cannot be resumed: expected the same inputs, or --overwrite to "
                  "start over)");
    }
    throw Error(path +
                ": the scene reads other input files than the run did (cannot be resumed: expected the "
                "same inputs, or --overwrite to start over)");
  }

  // Mode::resume: the file of an earlier run of the same scene, read to its last complete frame
  // (a killed writer may have extended some series and not others). Nothing is changed until
  // continue_run(): a refused resume leaves the file and its sidecar as they were.
  void open_for_resume(hid_t fapl, const RunInfo& info, std::size_t zones) {
    if (H5Fis_hdf5(path.c_str()) <= 0)
      throw Error(path + ": not an HDF5 file (expected the output of an earlier run to resume)");
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl);
    if (f < 0)
      throw Error(path + ": cannot be opened to resume" + hdf5_reason() + " (expected an isochor output file)");
    file = H(f, H5Fclose);
    const std::string command = read_string_attribute(file, "command");
    if (command != info.command)
      throw Error(path + ": was written by `isochor " + (command.empty() ? "?" : command) + "`, not `isochor " +
                  info.command + "` (cannot be resumed)");
    const std::string scene = read_string_attribute(file, "scene");
    if (scene != info.scene_text)
      throw Error(path + ": was written from a different scene (line " +
                  std::to_string(first_difference(scene, info.scene_text)) +
                  " of the scene as run differs; expected the same scene file and --set options, or --overwrite to "
                  "start over)");
    check_inputs(read_string_attribute(file, "inputs"), info.inputs);
    frames_group = H(checked(H5Gopen2(file, "frames", H5P_DEFAULT), "open /frames"), H5Gclose);
    xdmf_group = H(checked(H5Gopen2(frames_group, "xdmf", H5P_DEFAULT), "open /frames/xdmf"), H5Gclose);
    stats_group = H(checked(H5Gopen2(file, "stats", H5P_DEFAULT), "open /stats"), H5Gclose);
    {
      H mesh_group(checked(H5Gopen2(file, "mesh", H5P_DEFAULT), "open /mesh"), H5Gclose);
      zone_index = H5Lexists(mesh_group, "zone", H5P_DEFAULT) > 0;
    }
    if (H5Lexists(frames_group, "velocities", H5P_DEFAULT) <= 0)
      throw Error(path + ": has no velocities (written before runs could be resumed): cannot be resumed");
    time = std::make_unique<Series>(frames_group, "time", H5T_NATIVE_DOUBLE);
    positions = std::make_unique<Series>(frames_group, "positions", H5T_NATIVE_DOUBLE);
    velocities = std::make_unique<Series>(frames_group, "velocities", H5T_NATIVE_DOUBLE);
    if (H5Lexists(frames_group, "multipliers", H5P_DEFAULT) > 0)
      multipliers = std::make_unique<Series>(frames_group, "multipliers", H5T_NATIVE_DOUBLE);
    if (H5Lexists(frames_group, "collider_pose", H5P_DEFAULT) > 0)
      collider_pose = std::make_unique<Series>(frames_group, "collider_pose", H5T_NATIVE_DOUBLE);
    if (H5Lexists(frames_group, "collider_scale", H5P_DEFAULT) > 0)
      collider_scale = std::make_unique<Series>(frames_group, "collider_scale", H5T_NATIVE_DOUBLE);
    if (H5Lexists(frames_group, "bone_pose", H5P_DEFAULT) > 0)
      bone_pose = std::make_unique<Series>(frames_group, "bone_pose", H5T_NATIVE_DOUBLE);
    if (H5Lexists(frames_group, "activation", H5P_DEFAULT) > 0)
      activation = std::make_unique<Series>(frames_group, "activation", H5T_NATIVE_DOUBLE);
    volume = std::make_unique<Series>(frames_group, "volume", H5T_NATIVE_DOUBLE);
    energy = std::make_unique<Series>(frames_group, "energy", H5T_NATIVE_DOUBLE);
    if (positions->row.at(0) != static_cast<hsize_t>(nodes) || volume->row.at(0) != 1 + zones)
      throw Error(path + ": its mesh or zones differ from the scene's (a mesh file changed since?): cannot be resumed");
    if (pressure) pressure_series = std::make_unique<Series>(frames_group, "pressure", H5T_NATIVE_DOUBLE);
    for (const char* name : {"load", "contact"})
      if (H5Lexists(frames_group, name, H5P_DEFAULT) > 0)
        node_series[name] = std::make_unique<Series>(frames_group, name, H5T_NATIVE_DOUBLE);
    H5G_info_t g{};
    check(H5Gget_info(stats_group, &g), "list /stats");
    for (hsize_t i = 0; i < g.nlinks; ++i) {
      char name[256];
      if (H5Lget_name_by_idx(stats_group, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT) < 0)
        continue;
      stats.emplace(name, std::make_unique<Series>(stats_group, name, H5T_NATIVE_DOUBLE));
    }
    hsize_t complete = time->rows();
    for (Series* series : all_series()) complete = std::min(complete, series->rows());
    if (complete == 0) throw Error(path + ": has no complete frame to resume from (run it again with --overwrite)");
    frames = static_cast<int>(complete);
    resume_zones = zones;
    resume_pending = true;
    resume.frame = frames - 1;
    resume.status = read_string_attribute(file, "status");
    time->read(complete - 1, &resume.time);
    resume.positions.resize(3, nodes);
    resume.velocities.resize(3, nodes);
    positions->read(complete - 1, resume.positions.data());
    velocities->read(complete - 1, resume.velocities.data());
    if (multipliers) {
      resume.multipliers.resize(multipliers->row.at(0));
      multipliers->read(complete - 1, resume.multipliers.data());
    }
    for (auto& [name, series] : stats) series->read(complete - 1, &resume.stats[name]);
  }

  // The file changed only once the resume is accepted: the half-written frame cut, the last
  // stop's reasons removed, the sidecar restarted, the status "running".
  void continue_run() {
    resume_pending = false;
    cut_frames(frames);
    for (const char* a : {"failed_at_time", "failure", "interrupted_at", "signal"}) delete_attribute(stats_group, a);
    std::vector<double> times(static_cast<std::size_t>(frames));
    check(H5Dread(time->ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, times.data()), "read /frames/time");
    string_attribute(file, "status", "running");
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), "flush");
    start_xdmf(times);
    start_measuring(resume_zones);
  }
};

// Before anything is written: the path is an output's (not a directory, not the sidecar's), an
// existing file is allowed only as the mode says, its directory exists, and it is locked (a
// second writer fails here and leaves the file alone).
void OutputWriter::Impl::lock_path(Mode mode, const RunInfo& info) {
  std::error_code ec;
  const std::string xp = xdmf_file();
  if (xp == path)
    throw Error(path + ": the XDMF sidecar would overwrite the output itself (expected an output path ending in .h5)");
  if (std::filesystem::is_directory(path, ec)) throw Error(path + ": is a directory (expected an output file path)");
  if (std::filesystem::is_directory(xp, ec))
    throw Error(xp + ": is a directory (the run's XDMF sidecar is written there; expected a file or nothing)");
  check_output_file(path, info.input_files, "the " + info.command + "'s output");
  check_output_file(xp, info.input_files, "the " + info.command + "'s XDMF sidecar");
  existed = std::filesystem::exists(path, ec);
  if (mode == Mode::create && (existed || std::filesystem::exists(xp, ec)))
    throw Error((existed ? path : xp) + ": exists (pass --overwrite to replace it" +
                (existed && info.command == "run" ? ", or --resume to continue the run in it" : "") + ")");
  if (mode == Mode::resume && !existed)
    throw Error(path + ": no such file to resume (expected the output of an earlier run)");
  auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(path + ": cannot create the directory " + dir.string() + " (" + ec.message() + ")");
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported by Error, not printed
  lock_fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd < 0) throw Error(path + ": cannot be created (" + std::strerror(errno) + ")");
  if (!try_lock(lock_fd)) {
    ::close(lock_fd);
    lock_fd = -1;
    throw Error(path + ": another process is writing it (one writer per output: wait for it, or choose another path)");
  }
}

// Default format bounds: the superblock then has no "open for writing" flag, so a file whose
// writer was killed opens without h5clear.
// A metadata cache of 1 MB, fixed: HDF5's default grows to 32 MB as a long run adds objects,
// and the flush after every frame walks every cached entry (100,000 frames of a small mesh:
// resident memory 72 -> 82 MB and the last frames written at a third of the first ones' rate;
// with 1 MB, 47 MB throughout and the rate within noise, bench/bench_output.cpp).
// HDF5's own file locking (flock) is off: the writer's lock keeps writers apart, and a reader
// that holds HDF5's shared lock (isochor info, h5py, ParaView on a running file) would otherwise
// make the writer's open or create fail.
static H file_access() {
  H fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  check(H5Pset_file_locking(fapl, false, true), "file locking");
  H5AC_cache_config_t c;
  c.version = H5AC__CURR_CACHE_CONFIG_VERSION;
  check(H5Pget_mdc_config(fapl, &c), "metadata cache configuration");
  c.set_initial_size = true;
  c.initial_size = c.max_size = 1024 * 1024;
  c.min_size = c.max_size / 4;
  check(H5Pset_mdc_config(fapl, &c), "metadata cache configuration");
  return fapl;
}

// The root attributes: status, the scene and where it came from, the command, the version, and
// the up direction a viewer turns upward.
void OutputWriter::Impl::write_header(const RunInfo& info) {
  string_attribute(file, "status", "running");
  string_attribute(file, "scene", info.scene_text);
  string_attribute(file, "scene_file", info.scene_file);
  string_attribute(file, "inputs", info.inputs);
  // Where the scene's relative file names (meshes, paint) resolve, for tools that read the run
  // from another directory.
  if (!info.scene_file.empty()) {
    std::error_code ec;
    const std::filesystem::path dir = std::filesystem::absolute(info.scene_file, ec).parent_path();
    string_attribute(file, "scene_directory", ec ? std::string() : dir.string());
  }
  string_attribute(file, "command", info.command);
  string_attribute(file, "isochor_version", isochor_version());
  string_attribute(file, "git_revision", isochor_git_revision());
  if (!info.scene.up_source.empty()) {
    vector_attribute(file, "up", info.scene.up.data(), 3);
    string_attribute(file, "up_source", info.scene.up_source);
  }
}

// /mesh: rest positions, tets, surface, rest volumes, node sets, and each tet's zone for viewers.
void OutputWriter::Impl::write_mesh(const Mesh& mesh, const Zones& zones) {
  H g = group(file, "mesh");
  write_array(g, "rest_positions", H5T_NATIVE_DOUBLE, {static_cast<hsize_t>(nodes), 3}, mesh.rest_positions().data());
  write_array(g, "tets", H5T_NATIVE_INT, {static_cast<hsize_t>(tets), 4}, mesh.tets().data());
  write_array(g, "surface", H5T_NATIVE_INT, {mesh.surface().size(), 3}, mesh.surface().data());
  write_array(g, "rest_volumes", H5T_NATIVE_DOUBLE, {static_cast<hsize_t>(tets)}, mesh.rest_volumes().data());
  H sets = group(g, "node_sets");
  for (const auto& [name, set] : mesh.node_sets) write_array(sets, name, H5T_NATIVE_INT, {set.size()}, set.data());
  // One zone per tet for viewers (ParaView colours by it): the index, in /frames/volume's
  // column order less "total", of the smallest zone that holds the tet; -1 in none.
  if (zones.empty()) return;
  const std::size_t T = static_cast<std::size_t>(tets);
  std::vector<int> zone(T, -1);
  std::vector<std::size_t> size_of(T, 0);
  for (std::size_t z = 0; z < zones.size(); ++z)
    for (int t : zones[z].second)
      if (zone[static_cast<std::size_t>(t)] < 0 || zones[z].second.size() < size_of[static_cast<std::size_t>(t)]) {
        zone[static_cast<std::size_t>(t)] = static_cast<int>(z);
        size_of[static_cast<std::size_t>(t)] = zones[z].second.size();
      }
  write_array(g, "zone", H5T_NATIVE_INT, {T}, zone.data());
  std::string names;
  for (const auto& z : zones) names += (names.empty() ? "" : ",") + z.first;
  H d(checked(H5Dopen2(g, "zone", H5P_DEFAULT), "open /mesh/zone"), H5Dclose);
  string_attribute(d, "zones", names);
  zone_index = true;
}

// /NAME/<k>: one group per record, named by its index and holding its name, filled by `write`.
template <class Record, class Write>
void indexed_groups(hid_t file, const char* name, const std::vector<Record>& records, Write&& write) {
  H g = group(file, name);
  for (std::size_t k = 0; k < records.size(); ++k) {
    H one = group(g, std::to_string(k));
    string_attribute(one, "name", records[k].name);
    write(one, records[k]);
  }
}

// /colliders/<k>: one group per collider in the scene's order (the index of its column in
// /frames/collider_pose), with its name, shape, dimensions and rest pose; a mesh's surface.
void OutputWriter::Impl::write_colliders(const std::vector<ColliderRecord>& colliders) {
  indexed_groups(file, "colliders", colliders, [](hid_t one, const ColliderRecord& c) {
    string_attribute(one, "shape", c.shape);
    for (const auto& [name, value] : c.dimensions) number_attribute(one, name, value);
    vector_attribute(one, "rest_pose", c.rest_pose.data(), 12);
    if (c.shape != "mesh") return;
    write_array(one, "vertices", H5T_NATIVE_DOUBLE, {static_cast<hsize_t>(c.vertices.cols()), 3}, c.vertices.data());
    write_array(one, "triangles", H5T_NATIVE_INT, {c.triangles.size(), 3}, c.triangles.data());
  });
}

// /bones/<k>: one group per bone of the skeleton (the index of its row in /frames/bone_pose), with
// its name, parent (-1: none) and rest capsule (from, to, radius).
void OutputWriter::Impl::write_bones(const std::vector<BoneRecord>& bones) {
  if (bones.empty()) return;
  indexed_groups(file, "bones", bones, [](hid_t one, const BoneRecord& b) {
    number_attribute(one, "parent", b.parent);
    vector_attribute(one, "from", b.from.data(), 3);
    vector_attribute(one, "to", b.to.data(), 3);
    number_attribute(one, "radius", b.radius);
  });
}

// /muscles: the names (attribute `names`, the columns of /frames/activation), each tet's muscle
// (`tet_muscle`, -1: none) and its rest fibre direction (`tet_fibre`, tets x 3).
void OutputWriter::Impl::write_muscles(const SceneRecord& scene) {
  if (scene.muscles.empty()) return;
  H g = group(file, "muscles");
  std::string names;
  for (const std::string& n : scene.muscles) names += (names.empty() ? "" : ",") + n;
  string_attribute(g, "names", names);
  write_array(g, "tet_muscle", H5T_NATIVE_INT, {scene.tet_muscle.size()}, scene.tet_muscle.data());
  write_array(g, "tet_fibre", H5T_NATIVE_DOUBLE, {static_cast<hsize_t>(scene.tet_fibre.cols()), 3},
              scene.tet_fibre.data());
}

// /render: an artist's mesh carried by the tets (attribute `source`, the file it came from): its
// rest vertices (`rest`, n x 3), `triangles` (m x 3), and each vertex's tet (`tet`) and barycentric
// weights there (`weights`, n x 4): at a frame, x_v = sum_k weights[v][k] positions[tets[tet[v]][k]].
void OutputWriter::Impl::write_render(const SceneRecord& scene) {
  if (!scene.render) return;
  const RenderMesh& r = *scene.render;
  H g = group(file, "render");
  string_attribute(g, "source", r.source);
  const hsize_t n = static_cast<hsize_t>(r.rest.cols());
  write_array(g, "rest", H5T_NATIVE_DOUBLE, {n, 3}, r.rest.data());
  write_array(g, "triangles", H5T_NATIVE_INT, {r.triangles.size(), 3}, r.triangles.data());
  write_array(g, "tet", H5T_NATIVE_INT, {n}, r.embedding.tet.data());
  write_array(g, "weights", H5T_NATIVE_DOUBLE, {n, 4}, r.embedding.weights.data());
  if (r.skin_bones.size() == static_cast<std::size_t>(n) && r.skin_weights.size() == r.skin_bones.size()) {
    write_array(g, "skin_bones", H5T_NATIVE_INT, {n, 4}, r.skin_bones.data());
    write_array(g, "skin_weights", H5T_NATIVE_DOUBLE, {n, 4}, r.skin_weights.data());
  }
}

void OutputWriter::Impl::append_optional(std::unique_ptr<Series>& series, const char* name,
                                         const std::vector<double>& values, std::vector<hsize_t> row, hsize_t k) {
  if (!series) {
    if (k > 0) throw Error(path + ": /frames/" + name + " appeared after the first frame");
    series = std::make_unique<Series>(frames_group, name, row, H5T_NATIVE_DOUBLE);
  }
  if (row != series->row) throw Error(path + ": a frame's " + name + " changed in size");
  series->append(k, values.data());
}

// /zones, /frames (its series and the sidecar's views) and /stats.
void OutputWriter::Impl::create_series(const Zones& zones) {
  H g = group(file, "zones");
  for (const auto& [name, set] : zones) write_array(g, name, H5T_NATIVE_INT, {set.size()}, set.data());
  frames_group = group(file, "frames");
  {
    // One link per frame (and two with pressures): tracking the links' creation order makes this
    // a new-style group (a fractal heap and a v2 B-tree of names, 1.8 format, the superblock
    // unchanged), whose insertions stay as cheap at the 100,000th frame as at the 10th.
    H gcpl(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
    check(H5Pset_link_creation_order(gcpl, H5P_CRT_ORDER_TRACKED), "link creation order");
    xdmf_group =
        H(checked(H5Gcreate2(frames_group, "xdmf", H5P_DEFAULT, gcpl, H5P_DEFAULT), "create group xdmf"), H5Gclose);
  }
  stats_group = group(file, "stats");
  time = std::make_unique<Series>(frames_group, "time", std::vector<hsize_t>{}, H5T_NATIVE_DOUBLE);
  positions = std::make_unique<Series>(frames_group, "positions", std::vector<hsize_t>{static_cast<hsize_t>(nodes), 3},
                                       H5T_NATIVE_DOUBLE);
  volume = std::make_unique<Series>(frames_group, "volume", std::vector<hsize_t>{1 + zones.size()}, H5T_NATIVE_DOUBLE);
  std::string columns = "total";
  for (const auto& z : zones) columns += "," + z.first;
  H vol(H5Dopen2(frames_group, "volume", H5P_DEFAULT), H5Dclose);
  string_attribute(vol, "columns", columns);
  energy = std::make_unique<Series>(frames_group, "energy", std::vector<hsize_t>{3}, H5T_NATIVE_DOUBLE);
  H en(H5Dopen2(frames_group, "energy", H5P_DEFAULT), H5Dclose);
  string_attribute(en, "columns", "kinetic,elastic,external");
  if (pressure)
    pressure_series = std::make_unique<Series>(frames_group, "pressure",
                                               std::vector<hsize_t>{static_cast<hsize_t>(tets)}, H5T_NATIVE_DOUBLE);
}

OutputWriter::OutputWriter(const std::string& path, const Mesh& mesh, const Zones& zones, const RunInfo& info,
                           bool pressure, Mode mode)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = path;
  m.h5_name = std::filesystem::path(path).filename().string();
  m.nodes = mesh.num_nodes();
  m.tets = mesh.num_tets();
  m.pressure = pressure;
  m.lock_path(mode, info);
  const H fapl = file_access();
  if (mode == Mode::resume) {
    m.open_for_resume(fapl, info, zones.size());
    return;
  }
  hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  if (f < 0) {
    const std::string reason = hdf5_reason();
    std::error_code ec;
    if (!m.existed) std::filesystem::remove(path, ec);
    throw Error(path + ": cannot be created" + reason);
  }
  m.file = H(f, H5Fclose);
  try {
    m.write_header(info);
    m.write_mesh(mesh, zones);
    m.write_colliders(info.scene.colliders);
    m.write_bones(info.scene.bones);
    m.write_muscles(info.scene);
    m.write_render(info.scene);
    m.create_series(zones);
    check(H5Fflush(m.file, H5F_SCOPE_GLOBAL), "flush");
  } catch (const Error& e) {  // a full disk or a size limit before the first frame: nothing is kept
    discard();
    throw Error(path + ": cannot be written (" + e.what() + "); nothing was kept");
  }
  // A frame's bytes before any is measured: positions, velocities, loads, pressures, the
  // scalars and their per-frame views.
  m.start_measuring(zones.size());
}

OutputWriter::~OutputWriter() {
  try {
    close();
  } catch (...) {
  }
}

void OutputWriter::write_frame(const Frame& f) {
  Impl& m = *impl_;
  if (!m.file.valid()) throw Error(m.path + ": the output is closed");
  if (!f.positions || f.positions->cols() != m.nodes)
    throw Error(m.path + ": a frame needs the positions of every node");
  if (f.velocities && f.velocities->cols() != m.nodes) throw Error(m.path + ": a frame's velocities need every node");
  const hsize_t k = static_cast<hsize_t>(m.frames);
  if (f.volumes.size() != m.volume->row[0])
    throw Error(m.path + ": a frame needs " + std::to_string(m.volume->row[0]) + " volumes (total and each zone)");
  m.ensure_room(m.frames);
  try {
    m.append_frame(f, k);
  } catch (const Error& e) {
    // Whatever the frame extended is cut back, so that the file ends at the frame before it.
    try {
      m.cut_frames(m.frames);
      H5Fflush(m.file, H5F_SCOPE_GLOBAL);
    } catch (...) {
    }
    H5Eclear2(H5E_DEFAULT);
    throw Error(m.path + ": frame " + std::to_string(k) + " (t = " + std::to_string(f.time) +
                " s) could not be written: " + e.what() +
                (k > 0 ? "; frames 0-" + std::to_string(k - 1) + " are intact" : ""));
  }
  m.frames++;
  m.measure_growth();
  m.append_xdmf(m.frames - 1, f.time);
}

void OutputWriter::Impl::append_frame(const Frame& f, hsize_t k) {
  Impl& m = *this;
  m.time->append(k, &f.time);
  m.positions->append(k, f.positions->data());
  if (f.velocities) {
    if (!m.velocities) {
      if (k > 0) throw Error(m.path + ": velocities appeared after the first frame");
      m.velocities = std::make_unique<Series>(
          m.frames_group, "velocities", std::vector<hsize_t>{static_cast<hsize_t>(m.nodes), 3}, H5T_NATIVE_DOUBLE);
    }
    m.velocities->append(k, f.velocities->data());
  }
  if (f.multipliers && !f.multipliers->empty()) {
    if (!m.multipliers) {
      if (k > 0) throw Error(m.path + ": multipliers appeared after the first frame");
      m.multipliers = std::make_unique<Series>(m.frames_group, "multipliers",
                                               std::vector<hsize_t>{f.multipliers->size()}, H5T_NATIVE_DOUBLE);
    }
    if (f.multipliers->size() != m.multipliers->row[0])
      throw Error(m.path + ": a frame's multipliers changed in number");
    m.multipliers->append(k, f.multipliers->data());
  }
  if (f.collider_poses && !f.collider_poses->empty())
    m.append_optional(m.collider_pose, "collider_pose", *f.collider_poses, {f.collider_poses->size() / 12, 12}, k);
  if (f.collider_scales && !f.collider_scales->empty())
    m.append_optional(m.collider_scale, "collider_scale", *f.collider_scales, {f.collider_scales->size()}, k);
  if (f.bone_poses && !f.bone_poses->empty())
    m.append_optional(m.bone_pose, "bone_pose", *f.bone_poses, {f.bone_poses->size() / 12, 12}, k);
  if (f.activations && !f.activations->empty())
    m.append_optional(m.activation, "activation", *f.activations, {f.activations->size()}, k);
  m.volume->append(k, f.volumes.data());
  m.energy->append(k, f.energy.data());
  m.add_frame_view("/frames/positions", m.frames, 3, "position");
  if (m.pressure_series) {
    if (!f.pressure || static_cast<int>(f.pressure->size()) != m.tets)
      throw Error(m.path + ": pressure output is on but a frame has no pressure per tet");
    m.pressure_series->append(k, f.pressure->data());
    m.add_frame_view("/frames/pressure", m.frames, 0, "pressure");
  }
  for (const auto& [name, field] : {std::pair<const char*, const Points*>{"load", f.loads}, {"contact", f.contact}}) {
    if (!field) continue;
    if (field->cols() != m.nodes) throw Error(m.path + ": a frame's " + name + " needs every node");
    std::unique_ptr<Series>& series = m.node_series[name];
    if (!series) {
      if (k > 0) throw Error(m.path + ": " + name + " appeared after the first frame");
      series = std::make_unique<Series>(m.frames_group, name, std::vector<hsize_t>{static_cast<hsize_t>(m.nodes), 3},
                                        H5T_NATIVE_DOUBLE);
    }
    series->append(k, field->data());
    m.add_frame_view(std::string("/frames/") + name, m.frames, 3, name);
  }
  for (const auto& [name, value] : f.stats) {
    auto it = m.stats.find(name);
    if (it == m.stats.end()) {
      it = m.stats
               .emplace(name, std::make_unique<Series>(m.stats_group, name, std::vector<hsize_t>{}, H5T_NATIVE_DOUBLE))
               .first;
      const double missing = std::numeric_limits<double>::quiet_NaN();  // frames before it appeared
      for (hsize_t j = 0; j < k; ++j) it->second->append(j, &missing);
    }
    it->second->append(k, &value);
  }
  check(H5Fflush(m.file, H5F_SCOPE_GLOBAL), "flush");
}

void OutputWriter::set_stat(const std::string& name, double value) {
  number_attribute(impl_->stats_group, name, value);
}
void OutputWriter::set_stat(const std::string& name, const std::string& value) {
  string_attribute(impl_->stats_group, name, value);
}

void OutputWriter::set_status(const std::string& status) {
  string_attribute(impl_->file, "status", status);
  check(H5Fflush(impl_->file, H5F_SCOPE_GLOBAL), "flush");
}

void OutputWriter::continue_run() { impl_->continue_run(); }

const ResumePoint& OutputWriter::resume_point() const { return impl_->resume; }

void hdf5_no_cleanup_at_exit() { H5dont_atexit(); }

double output_room_bytes(const std::string& path) { return std::min(free_bytes(path), file_size_limit()); }

bool output_is_being_written(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  struct flock l {};
  l.l_type = F_WRLCK;
  l.l_whence = SEEK_SET;
  const bool locked = ::fcntl(fd, F_OFD_GETLK, &l) == 0 && l.l_type != F_UNLCK;
  ::close(fd);
  return locked;
}

void OutputWriter::close() {
  Impl& m = *impl_;
  if (!m.file.valid()) return;
  // No frames: the sidecar still names the run's (empty) series; a resume not continued leaves it.
  if (!m.sidecar.is_open() && !m.resume_pending) m.start_xdmf();
  m.close_xdmf();
  m.time.reset();
  m.positions.reset();
  m.velocities.reset();
  m.multipliers.reset();
  m.collider_pose.reset();
  m.collider_scale.reset();
  m.bone_pose.reset();
  m.activation.reset();
  m.volume.reset();
  m.energy.reset();
  m.pressure_series.reset();
  m.node_series.clear();
  m.stats.clear();
  m.frames_group.reset();
  m.xdmf_group.reset();
  m.stats_group.reset();
  m.file.reset();
  if (m.lock_fd >= 0) ::close(m.lock_fd);  // the file is complete: other writers may have it
  m.lock_fd = -1;
}

void OutputWriter::discard() {
  Impl& m = *impl_;
  if (m.resume_pending || m.frames > 0)
    throw Error(m.path + ": holds frames (a run's output is never discarded once written)");
  try {
    close();
  } catch (const Error&) {  // the file is removed either way
  }
  std::error_code ec;
  std::filesystem::remove(m.path, ec);
  std::filesystem::remove(m.xdmf_file(), ec);
}

int OutputWriter::frames_written() const { return impl_->frames; }
const std::string& OutputWriter::path() const { return impl_->path; }
std::string OutputWriter::xdmf_path() const { return impl_->xdmf_file(); }

}  // namespace isochor
