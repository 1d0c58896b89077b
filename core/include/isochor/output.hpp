// One HDF5 file per run (schema in docs/output.md) and an XDMF sidecar that ParaView opens as a
// time series. Frames are flushed as they are written: a killed run keeps every finished frame.
#pragma once
#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "isochor/mesh.hpp"

namespace isochor {

struct RunInfo {
  std::string scene_text;  // the scene as run
  std::string scene_file;  // where it came from
  std::string command;     // e.g. "run", "mesh"
};

struct Frame {
  double time = 0.0;
  const Points* positions = nullptr;     // all nodes
  std::vector<double> volumes;           // total, then each zone (in the order given at open)
  std::array<double, 3> energy{0, 0, 0};  // kinetic, elastic, external potential
  const std::vector<double>* pressure = nullptr;  // per tet, when pressure output is on
  const Points* loads = nullptr;  // the applied load on every node (N), when the scene has loads
  std::vector<std::pair<std::string, double>> stats;  // per-frame series under /stats
};

class OutputWriter {
 public:
  // `zones` are written under /zones and name the columns of /frames/volume.
  OutputWriter(const std::string& path, const Mesh& mesh,
               const std::vector<std::pair<std::string, std::vector<int>>>& zones, const RunInfo& info,
               bool pressure);
  ~OutputWriter();
  OutputWriter(const OutputWriter&) = delete;
  OutputWriter& operator=(const OutputWriter&) = delete;

  void write_frame(const Frame& f);
  // Attributes on /stats (run totals).
  void set_stat(const std::string& name, double value);
  void set_stat(const std::string& name, const std::string& value);
  // Closes the file (also done by the destructor).
  void close();

  int frames_written() const;
  const std::string& path() const;
  std::string xdmf_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The version and git revision compiled into this build.
const char* isochor_version();
const char* isochor_git_revision();

}  // namespace isochor
