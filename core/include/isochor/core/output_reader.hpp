// Reading a run's HDF5 file back: the summary that `isochor info` prints and per-frame positions.
#pragma once
#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "isochor/core/mesh.hpp"

namespace isochor {

class RunFile {
 public:
  explicit RunFile(const std::string& path);
  ~RunFile();
  int num_nodes() const;
  int num_tets() const;
  int num_frames() const;
  std::vector<std::string> zone_names() const;  // in /frames/volume column order
  std::map<std::string, std::size_t> zone_sizes() const;
  std::vector<double> times() const;
  std::vector<std::vector<double>> volumes() const;     // per frame: total, then zones
  std::vector<std::array<double, 3>> energies() const;  // per frame: kinetic, elastic, external
  std::vector<Tri> surface() const;
  Points rest_positions() const;
  std::vector<Tet> tets() const;  // /mesh/tets
  Points positions(int frame) const;
  Points velocities(int frame) const;              // every node (m/s): runs written since they could be resumed
  std::vector<double> pressures(int frame) const;  // per tet; the run must have output.pressure = true
  Points loads(int frame) const { return node_vectors("load", frame); }  // per node (N); the scene must have [[load]]
  Points contact(int frame) const {
    return node_vectors("contact", frame);
  }                                                               // per node (N); the scene must have colliders
  Points node_vectors(const std::string& name, int frame) const;  // /frames/<name>
  // A [character]'s render mesh (/render): its vertices and triangles; {0, 0} where there is none.
  std::array<std::size_t, 2> render_size() const;
  std::map<std::string, std::string> attributes() const;           // root attributes (strings)
  std::map<std::string, double> stat_totals() const;               // numeric attributes of /stats
  std::string stat_text(const std::string& name) const;            // a string attribute of /stats ("" if none)
  std::map<std::string, std::vector<double>> stat_series() const;  // datasets under /stats

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The summary printed by `isochor info`.
std::string describe_run(const std::string& path);

// Writes the surface of each frame as <dir>/<prefix>_<frame>.obj (frames numbered from 0);
// returns the number of files written.
int export_obj_sequence(const std::string& h5_path, const std::string& dir, const std::string& prefix);

}  // namespace isochor
