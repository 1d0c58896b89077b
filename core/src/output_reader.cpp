#include "isochor/core/input_file.hpp"
#include "isochor/core/output_reader.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "isochor/base/error.hpp"
#include "hdf5_util.hpp"
#include "isochor/core/output.hpp"

namespace isochor {

struct RunFile::Impl {
  std::string path;
  hid_t file = -1;

  std::vector<hsize_t> dims(const std::string& name) const {
    hid_t ds = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
    if (ds < 0) throw Error(path + ": has no dataset " + name + " (expected an isochor output file)");
    hid_t sp = H5Dget_space(ds);
    int rank = H5Sget_simple_extent_ndims(sp);
    std::vector<hsize_t> d(std::max(rank, 0));
    H5Sget_simple_extent_dims(sp, d.data(), nullptr);
    H5Sclose(sp);
    H5Dclose(ds);
    return d;
  }
  template <class T>
  std::vector<T> read(const std::string& name, hid_t type) const {
    auto d = dims(name);
    std::size_t n = 1;
    for (hsize_t x : d) n *= x;
    std::vector<T> out(n);
    hid_t ds = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
    herr_t st = n ? H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) : 0;
    H5Dclose(ds);
    if (st < 0) throw Error(path + ": cannot read " + name);
    return out;
  }
  std::string string_attr(hid_t loc, const char* name) const {
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
    if (a < 0) return "";
    hid_t t = H5Aget_type(a);
    std::string out;
    if (H5Tis_variable_str(t) > 0) {
      char* p = nullptr;
      hid_t mt = H5Tcopy(H5T_C_S1);
      H5Tset_size(mt, H5T_VARIABLE);
      H5Tset_cset(mt, H5Tget_cset(t));
      if (H5Aread(a, mt, &p) >= 0 && p) out = p;
      if (p) H5free_memory(p);
      H5Tclose(mt);
    }
    H5Tclose(t);
    H5Aclose(a);
    return out;
  }
};

RunFile::RunFile(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  check_input_file(path, "an isochor .h5 output", input_limits::kRun);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (H5Fis_hdf5(path.c_str()) <= 0) throw Error(path + ": not an HDF5 file (expected an isochor .h5 output)");
  // Read without HDF5's file lock, which would stop a run from opening the file to write or
  // resume it while it is read (a file being written is consistent up to its last flushed frame).
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_file_locking(fapl, false, true);
  impl_->file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl);
  H5Pclose(fapl);
  if (impl_->file < 0)
    throw Error(path + ": cannot be opened" + h5::hdf5_reason() + " (expected an isochor .h5 output)");
  impl_->dims("/mesh/tets");
}

RunFile::~RunFile() {
  if (impl_->file >= 0) H5Fclose(impl_->file);
}

int RunFile::num_nodes() const { return static_cast<int>(impl_->dims("/mesh/rest_positions")[0]); }
int RunFile::num_tets() const { return static_cast<int>(impl_->dims("/mesh/tets")[0]); }
int RunFile::num_frames() const { return static_cast<int>(impl_->dims("/frames/time")[0]); }
std::vector<double> RunFile::times() const { return impl_->read<double>("/frames/time", H5T_NATIVE_DOUBLE); }

std::vector<std::string> RunFile::zone_names() const {
  hid_t ds = H5Dopen2(impl_->file, "/frames/volume", H5P_DEFAULT);
  std::string cols = impl_->string_attr(ds, "columns");
  H5Dclose(ds);
  std::vector<std::string> out;
  std::stringstream s(cols);
  for (std::string c; std::getline(s, c, ',');) out.push_back(c);
  if (!out.empty()) out.erase(out.begin());  // "total"
  return out;
}

std::map<std::string, std::size_t> RunFile::zone_sizes() const {
  std::map<std::string, std::size_t> out;
  for (const std::string& z : zone_names()) out[z] = impl_->dims("/zones/" + z)[0];
  return out;
}

std::vector<std::vector<double>> RunFile::volumes() const {
  auto d = impl_->dims("/frames/volume");
  auto flat = impl_->read<double>("/frames/volume", H5T_NATIVE_DOUBLE);
  std::vector<std::vector<double>> out(d[0]);
  for (hsize_t f = 0; f < d[0]; ++f) out[f].assign(flat.begin() + f * d[1], flat.begin() + (f + 1) * d[1]);
  return out;
}

std::vector<std::array<double, 3>> RunFile::energies() const {
  auto flat = impl_->read<double>("/frames/energy", H5T_NATIVE_DOUBLE);
  std::vector<std::array<double, 3>> out(flat.size() / 3);
  for (std::size_t f = 0; f < out.size(); ++f) out[f] = {flat[3 * f], flat[3 * f + 1], flat[3 * f + 2]};
  return out;
}

namespace {

// A mesh's cells of `width` nodes each, read whole; every node index must be one of the file's
// nodes (a file edited by hand or written by another program is refused, not indexed out of range).
template <std::size_t width>
std::vector<std::array<int, width>> read_cells(const std::string& path, const std::vector<int>& flat, int nodes,
                                               const std::string& name) {
  if (flat.size() % width != 0)
    throw Error(path + ": " + name + " holds " + std::to_string(flat.size()) + " indices, not " +
                std::to_string(width) + " per row (expected an isochor output file)");
  for (std::size_t i = 0; i < flat.size(); ++i)
    if (flat[i] < 0 || flat[i] >= nodes)
      throw Error(path + ": " + name + " row " + std::to_string(i / width) + " refers to node " +
                  std::to_string(flat[i]) + " of " + std::to_string(nodes) + " (expected an isochor output file)");
  std::vector<std::array<int, width>> out(flat.size() / width);
  for (std::size_t i = 0; i < out.size(); ++i)
    for (std::size_t k = 0; k < width; ++k) out[i][k] = flat[width * i + k];
  return out;
}

}  // namespace

std::vector<Tri> RunFile::surface() const {
  return read_cells<3>(impl_->path, impl_->read<int>("/mesh/surface", H5T_NATIVE_INT), num_nodes(), "/mesh/surface");
}

std::vector<Tet> RunFile::tets() const {
  return read_cells<4>(impl_->path, impl_->read<int>("/mesh/tets", H5T_NATIVE_INT), num_nodes(), "/mesh/tets");
}

Points RunFile::rest_positions() const {
  auto flat = impl_->read<double>("/mesh/rest_positions", H5T_NATIVE_DOUBLE);
  return Eigen::Map<Points>(flat.data(), 3, static_cast<Eigen::Index>(flat.size() / 3));
}

namespace {
// Reads row `frame` (cols values) of a 2-D (F, cols) or 3-D (F, rows, 3) frame series.
void read_frame_row(hid_t file, const std::string& path, const char* name, int frame, int rank, hsize_t rows,
                    double* out) {
  hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
  if (ds < 0) throw Error(path + ": " + name + " is not in this run");
  hid_t fs = H5Dget_space(ds);
  hsize_t start[3] = {static_cast<hsize_t>(frame), 0, 0}, count[3] = {1, rows, 3};
  H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, nullptr, count, nullptr);
  hid_t ms = H5Screate_simple(rank, count, nullptr);
  herr_t st = H5Dread(ds, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, out);
  H5Sclose(ms);
  H5Sclose(fs);
  H5Dclose(ds);
  if (st < 0) throw Error(path + ": cannot read " + name + " of frame " + std::to_string(frame));
}
}  // namespace

Points RunFile::positions(int frame) const {
  if (frame < 0 || frame >= num_frames())
    throw Error(impl_->path + ": frame " + std::to_string(frame) + " does not exist");
  Points x(3, num_nodes());
  read_frame_row(impl_->file, impl_->path, "/frames/positions", frame, 3, static_cast<hsize_t>(num_nodes()), x.data());
  return x;
}

Points RunFile::velocities(int frame) const {
  if (frame < 0 || frame >= num_frames())
    throw Error(impl_->path + ": frame " + std::to_string(frame) + " does not exist");
  Points v(3, num_nodes());
  read_frame_row(impl_->file, impl_->path, "/frames/velocities", frame, 3, static_cast<hsize_t>(num_nodes()), v.data());
  return v;
}

std::vector<double> RunFile::pressures(int frame) const {
  if (frame < 0 || frame >= num_frames())
    throw Error(impl_->path + ": frame " + std::to_string(frame) + " does not exist");
  std::vector<double> p(num_tets());
  read_frame_row(impl_->file, impl_->path, "/frames/pressure", frame, 2, static_cast<hsize_t>(num_tets()), p.data());
  return p;
}

Points RunFile::node_vectors(const std::string& name, int frame) const {
  if (frame < 0 || frame >= num_frames())
    throw Error(impl_->path + ": frame " + std::to_string(frame) + " does not exist");
  Points f(3, num_nodes());
  read_frame_row(impl_->file, impl_->path, ("/frames/" + name).c_str(), frame, 3, static_cast<hsize_t>(num_nodes()),
                 f.data());
  return f;
}

std::map<std::string, std::string> RunFile::attributes() const {
  std::map<std::string, std::string> out;
  for (const char* k : {"scene", "scene_file", "command", "isochor_version", "git_revision", "status"})
    out[k] = impl_->string_attr(impl_->file, k);
  return out;
}

namespace {
herr_t collect_attr(hid_t loc, const char* name, const H5A_info_t*, void* data) {
  auto* out = static_cast<std::map<std::string, double>*>(data);
  hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  hid_t t = H5Aget_type(a);
  if (H5Tget_class(t) == H5T_FLOAT || H5Tget_class(t) == H5T_INTEGER) {
    double v;
    if (H5Aread(a, H5T_NATIVE_DOUBLE, &v) >= 0) (*out)[name] = v;
  }
  H5Tclose(t);
  H5Aclose(a);
  return 0;
}
herr_t collect_name(hid_t, const char* name, const H5L_info_t*, void* data) {
  static_cast<std::vector<std::string>*>(data)->push_back(name);
  return 0;
}
}  // namespace

std::string RunFile::stat_text(const std::string& name) const {
  hid_t g = H5Gopen2(impl_->file, "/stats", H5P_DEFAULT);
  if (g < 0) return "";
  std::string v = impl_->string_attr(g, name.c_str());
  H5Gclose(g);
  return v;
}

std::map<std::string, double> RunFile::stat_totals() const {
  std::map<std::string, double> out;
  hid_t g = H5Gopen2(impl_->file, "/stats", H5P_DEFAULT);
  if (g < 0) return out;
  H5Aiterate2(g, H5_INDEX_NAME, H5_ITER_INC, nullptr, collect_attr, &out);
  H5Gclose(g);
  return out;
}

std::map<std::string, std::vector<double>> RunFile::stat_series() const {
  std::vector<std::string> names;
  hid_t g = H5Gopen2(impl_->file, "/stats", H5P_DEFAULT);
  if (g < 0) return {};
  H5Literate(g, H5_INDEX_NAME, H5_ITER_INC, nullptr, collect_name, &names);
  H5Gclose(g);
  std::map<std::string, std::vector<double>> out;
  for (const std::string& n : names) out[n] = impl_->read<double>("/stats/" + n, H5T_NATIVE_DOUBLE);
  return out;
}

std::array<std::size_t, 2> RunFile::render_size() const {
  if (H5Lexists(impl_->file, "/render", H5P_DEFAULT) <= 0) return {0, 0};
  return {static_cast<std::size_t>(impl_->dims("/render/rest")[0]),
          static_cast<std::size_t>(impl_->dims("/render/triangles")[0])};
}

namespace {
// "  zones       N: name (k tets), ...": the first kListedZones by name (per-node 1-ring zones are
// thousands), then how many more.
std::string zones_line(const RunFile& r) {
  constexpr std::size_t kListedZones = 12;
  std::ostringstream s;
  auto zones = r.zone_sizes();
  s << "  zones       " << zones.size();
  std::size_t listed = 0;
  for (const auto& [name, n] : zones)
    if (listed++ < kListedZones) s << (listed == 1 ? ": " : ", ") << name << " (" << n << " tets)";
  if (zones.size() > kListedZones) s << ", and " << zones.size() - kListedZones << " more";
  s << "\n";
  return s.str();
}
}  // namespace

std::string describe_run(const std::string& path) {
  RunFile r(path);
  std::ostringstream s;
  auto attrs = r.attributes();
  s << path << "\n";
  s << "  written by  isochor " << attrs["isochor_version"] << " (" << attrs["git_revision"] << "), command "
    << attrs["command"] << ", scene " << attrs["scene_file"] << "\n";
  s << "  mesh        " << r.num_nodes() << " nodes, " << r.num_tets() << " tets, " << r.surface().size()
    << " surface triangles\n";
  if (const auto render = r.render_size(); render[0] > 0)
    s << "  render      " << render[0] << " vertices, " << render[1] << " triangles (the character's own mesh, "
      << "carried by the tets: isochor export --format glb)\n";
  s << zones_line(r);
  auto t = r.times();
  s << "  frames      " << t.size();
  if (!t.empty()) s << ", t = " << t.front() << " .. " << t.back() << " s";
  s << "\n";
  // What became of the run: the writer's lock says whether it is still running; the status
  // attribute what it said last (a killed writer leaves "running" behind, unlocked).
  if (attrs["command"] == "run") {
    auto totals = r.stat_totals();
    auto at = [&](const char* k) { return totals.count(k) ? totals[k] : std::nan(""); };
    const std::string status = attrs["status"];
    const std::string resume = t.empty() ? "; no frame to continue from (run it again with --overwrite)"
                                         : "; continue it with `isochor run " + attrs["scene_file"] + " --resume -o " +
                                               path + "` and the same --set options";
    s << "  status      ";
    if (output_is_being_written(path))
      s << "still being written (a running isochor holds its lock)";
    else if (status == "finished")
      s << "finished";
    else if (status == "interrupted")
      s << "interrupted at t = " << at("interrupted_at") << " s (signal " << at("signal") << ")" << resume;
    else if (status == "failed")
      s << "failed"
        << (std::isfinite(at("failed_at_time")) ? " at t = " + std::to_string(at("failed_at_time")) + " s" : "") << ": "
        << r.stat_text("failure") << resume;
    else if (status == "running")
      s << "unfinished: its writer stopped without closing it (killed?) after t = " << (t.empty() ? 0.0 : t.back())
        << " s" << resume;
    else
      s << "not recorded (written before runs recorded it)";
    s << "\n";
  }
  auto vol = r.volumes();
  if (!vol.empty()) {
    auto names = r.zone_names();
    names.insert(names.begin(), "total");
    s << "  volume drift (max |V - V0| / V0 over frames)\n";
    for (std::size_t c = 0; c < names.size(); ++c) {
      double v0 = vol.front()[c], worst = 0.0;
      for (const auto& row : vol) worst = std::max(worst, std::abs(row[c] - v0) / std::abs(v0));
      char buf[128];
      std::snprintf(buf, sizeof buf, "    %-20s V0 = %.6g, drift %.3e\n", names[c].c_str(), v0, worst);
      s << buf;
    }
  }
  auto series = r.stat_series();
  if (series.count("inverted_tets")) {
    const auto& inv = series["inverted_tets"];
    double worst = inv.empty() ? 0 : *std::max_element(inv.begin(), inv.end());
    s << "  inverted tets, most in one frame: " << worst << "\n";
  }
  auto totals = r.stat_totals();
  if (!totals.empty()) {
    s << "  solver statistics\n";
    for (const auto& [k, v] : totals) {
      char buf[128];
      std::snprintf(buf, sizeof buf, "    %-28s %.6g\n", k.c_str(), v);
      s << buf;
    }
  }
  return s.str();
}

int export_obj_sequence(const std::string& h5_path, const std::string& dir, const std::string& prefix) {
  // The files go into `dir` and nowhere else: a prefix is a file name's start, not a path.
  if (prefix.empty() || prefix.find('/') != std::string::npos || prefix == "." || prefix == "..")
    throw Error("--prefix " + prefix + ": expected the start of a file name (no '/'), e.g. frame");
  RunFile r(h5_path);
  auto surface = r.surface();  // read (and checked) before anything is created
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(dir + ": cannot create the directory (" + ec.message() + ")");
  // Only surface nodes are written, renumbered from 1 in index order.
  std::vector<int> nodes;
  for (const Tri& f : surface) nodes.insert(nodes.end(), f.begin(), f.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  std::vector<int> local(r.num_nodes(), -1);
  for (std::size_t i = 0; i < nodes.size(); ++i) local[nodes[i]] = static_cast<int>(i) + 1;
  const int F = r.num_frames();
  const int width = std::max(4, static_cast<int>(std::to_string(F).size()));
  for (int f = 0; f < F; ++f) {
    Points x = r.positions(f);
    std::string num = std::to_string(f);
    num.insert(0, static_cast<std::size_t>(std::max(0, width - static_cast<int>(num.size()))), '0');
    std::string file = (std::filesystem::path(dir) / (prefix + "_" + num + ".obj")).string();
    // Written beside and renamed into place: a failed write (a full disk) leaves no partial file;
    // never over a device, a FIFO or the run itself.
    check_output_file(file, {h5_path}, "an OBJ frame");
    const std::string part = file + ".part";
    {
      std::ofstream out(part);
      if (!out) throw Error(file + ": cannot be written");
      out.precision(9);
      out << "# isochor surface, frame " << f << "\n";
      for (int v : nodes) out << "v " << x(0, v) << " " << x(1, v) << " " << x(2, v) << "\n";
      for (const Tri& t : surface) out << "f " << local[t[0]] << " " << local[t[1]] << " " << local[t[2]] << "\n";
      out.flush();
      if (!out) {
        out.close();
        std::filesystem::remove(part, ec);
        throw Error(file + ": cannot be written (the disk is full?); frames 0 to " + std::to_string(f - 1) +
                    " were written");
      }
    }
    std::filesystem::rename(part, file, ec);
    if (ec) throw Error(file + ": cannot be written (" + ec.message() + ")");
  }
  return F;
}

}  // namespace isochor
