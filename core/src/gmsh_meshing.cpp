// Everything that goes through Gmsh's C++ API: curved shapes, .msh files, closed surfaces.
#include <Eigen/Geometry>
#include <fcntl.h>
#include <gmsh.h>
#include <omp.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <exception>
#include <fstream>
#include <functional>
#include <mutex>
#include <unordered_map>

#include "isochor/core/input_file.hpp"
#include "isochor/core/process.hpp"
#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"

namespace isochor {

namespace {

// Gmsh keeps global state: one session per process, used by one thread at a time. Gmsh sets
// OpenMP's thread count to its General.NumThreads (1 by default, and 1 here) when it initialises
// and whenever that option is set: the session meshes on one thread and gives the caller its
// OpenMP thread count back when it ends, else every element pass and CG product after a Gmsh mesh
// would run on one thread whatever OMP_NUM_THREADS says.
class GmshSession {
 public:
  explicit GmshSession(const std::string& model)
      : lock_(mutex()), exceptions_(std::uncaught_exceptions()), omp_threads_(omp_get_max_threads()) {
    static bool initialised = false;
    if (broken())
      throw Error(
          "Gmsh cannot be used again in this process: an earlier file or mesh failed inside it (expected a new "
          "process)");
    if (!initialised) {
      gmsh::initialize(0, nullptr, false);
      gmsh::option::setNumber("General.Terminal", 0);
      std::atexit([] {
        if (!broken()) gmsh::finalize();
      });
      initialised = true;
    }
    gmsh::clear();
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::option::setNumber("Mesh.RandomSeed", 1);
    gmsh::option::setNumber("Mesh.Algorithm3D", 1);
    // Options one mesher sets must not leak into the next (Gmsh 4.8 cannot restore defaults):
    // every option any of them sets is put back to Gmsh's default here.
    gmsh::option::setNumber("Mesh.MeshSizeMin", 0);
    gmsh::option::setNumber("Mesh.MeshSizeMax", 1e22);
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 1);
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 1);
    gmsh::logger::start();
    gmsh::model::add(model);
  }
  // A session that ends by an exception (a file Gmsh could not read, a mesh it could not make)
  // leaves Gmsh alone: its model may be half-built, and clearing it crashed inside Gmsh 4.8 on a
  // malformed .msh (found by the fuzzer). Gmsh is then not used again in this process.
  ~GmshSession() {
    omp_set_num_threads(omp_threads_);
    if (std::uncaught_exceptions() > exceptions_) {
      broken() = true;
      return;
    }
    gmsh::logger::stop();
    gmsh::clear();
  }
  static bool& broken() {
    static bool b = false;
    return b;
  }

  // The first error Gmsh logged since the session started, or "".
  static std::string first_error() {
    std::vector<std::string> log;
    gmsh::logger::get(log);
    for (const std::string& l : log)
      if (l.rfind("Error", 0) == 0) return l;
    return "";
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  int exceptions_;
  int omp_threads_;  // the caller's OpenMP thread count
};

struct Extracted {
  Points x;
  std::vector<Tet> tets;
  std::unordered_map<std::size_t, int> node_index;  // Gmsh node tag -> index before compaction
  std::unordered_map<std::size_t, int> tet_index;   // Gmsh element tag -> tet index
};

Extracted extract_tets(const std::string& what) {
  Extracted e;
  std::vector<std::size_t> tags;
  std::vector<double> coords, param;
  gmsh::model::mesh::getNodes(tags, coords, param, -1, -1, false, false);
  e.x.resize(3, static_cast<Eigen::Index>(tags.size()));
  for (std::size_t i = 0; i < tags.size(); ++i) {
    e.node_index[tags[i]] = static_cast<int>(i);
    e.x.col(i) = Eigen::Vector3d(coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]);
  }
  std::vector<int> types;
  gmsh::model::mesh::getElementTypes(types, 3);
  for (int t : types)
    if (t != 4) {
      std::string name;
      int dim, order, nn, np;
      std::vector<double> lc;
      gmsh::model::mesh::getElementProperties(t, name, dim, order, nn, lc, np);
      throw Error(what + ": contains 3-D elements of type \"" + name + "\", expected only linear 4-node tetrahedra");
    }
  std::vector<std::size_t> etags, enodes;
  gmsh::model::mesh::getElementsByType(4, etags, enodes);
  if (etags.empty()) throw Error(what + ": contains no tetrahedra (expected a volume mesh)");
  e.tets.resize(etags.size());
  for (std::size_t i = 0; i < etags.size(); ++i) {
    e.tet_index[etags[i]] = static_cast<int>(i);
    for (int k = 0; k < 4; ++k) {
      auto it = e.node_index.find(enodes[4 * i + k]);
      if (it == e.node_index.end())
        throw Error(what + ": element " + std::to_string(etags[i]) + " refers to missing node " +
                    std::to_string(enodes[4 * i + k]));
      e.tets[i][k] = it->second;
    }
  }
  return e;
}

Mesh finish(Extracted e, const std::string& what, std::map<std::string, std::vector<int>> zones,
            std::map<std::string, std::vector<int>> node_sets, std::map<std::string, Mesh::TetField> fields = {}) {
  compact_unused_nodes(e.x, e.tets, &node_sets);
  Mesh m(std::move(e.x), std::move(e.tets), what);
  for (auto& [k, v] : zones) std::sort(v.begin(), v.end());
  for (auto& [k, v] : node_sets) std::sort(v.begin(), v.end());
  m.zones = std::move(zones);
  m.node_sets = std::move(node_sets);
  m.tet_fields = std::move(fields);
  return m;
}

// What a Gmsh read or mesh hands back before isochor makes a Mesh of it.
struct RawMesh {
  Extracted e;
  std::map<std::string, std::vector<int>> zones, sets;
  std::map<std::string, Mesh::TetField> fields;
};

Mesh finish(RawMesh raw, const std::string& what) {
  return finish(std::move(raw.e), what, std::move(raw.zones), std::move(raw.sets), std::move(raw.fields));
}

template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
void put_vector(std::string& out, const std::vector<T>& v) {
  put(out, static_cast<std::uint64_t>(v.size()));
  out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}
void put_groups(std::string& out, const std::map<std::string, std::vector<int>>& g) {
  put(out, static_cast<std::uint64_t>(g.size()));
  for (const auto& [name, v] : g) {
    put_vector(out, std::vector<char>(name.begin(), name.end()));
    put_vector(out, v);
  }
}
void put_fields(std::string& out, const std::map<std::string, Mesh::TetField>& f) {
  put(out, static_cast<std::uint64_t>(f.size()));
  for (const auto& [name, field] : f) {
    put_vector(out, std::vector<char>(name.begin(), name.end()));
    put(out, field.components);
    put_vector(out, field.values);
  }
}
struct Reader {
  const std::string& in;
  std::size_t at = 0;
  template <class T>
  T get() {
    if (at + sizeof(T) > in.size()) throw Error("internal: a truncated mesh from the Gmsh child process");
    T v;
    std::memcpy(&v, in.data() + at, sizeof v);
    at += sizeof v;
    return v;
  }
  template <class T>
  std::vector<T> get_vector() {
    const auto n = get<std::uint64_t>();
    if (n > (in.size() - at) / sizeof(T)) throw Error("internal: a truncated mesh from the Gmsh child process");
    std::vector<T> v(n);
    std::memcpy(v.data(), in.data() + at, n * sizeof(T));
    at += n * sizeof(T);
    return v;
  }
  std::map<std::string, std::vector<int>> get_groups() {
    std::map<std::string, std::vector<int>> g;
    const auto n = get<std::uint64_t>();
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::vector<char> name = get_vector<char>();
      g[std::string(name.begin(), name.end())] = get_vector<int>();
    }
    return g;
  }
  std::map<std::string, Mesh::TetField> get_fields() {
    std::map<std::string, Mesh::TetField> f;
    const auto n = get<std::uint64_t>();
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::vector<char> name = get_vector<char>();
      Mesh::TetField& field = f[std::string(name.begin(), name.end())];
      field.components = get<int>();
      field.values = get_vector<double>();
    }
    return f;
  }
};

// Runs `f` (a Gmsh read or mesh) in a child process and returns what it made. Gmsh 4.8 crashes
// on some malformed files (the fuzzer found segfaults in getElementsByType and in clearing a
// half-read model): in the child, a crash is only the child's, and becomes an Error naming
// `what`. An Error in the child comes back as itself.
RawMesh in_child(const std::string& what, const std::string& expected, const std::function<RawMesh()>& f) {
  int fd[2];
  if (::pipe(fd) != 0) throw Error(what + ": cannot start the Gmsh process (" + std::strerror(errno) + ")");
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) throw Error(what + ": cannot start the Gmsh process (" + std::strerror(errno) + ")");
  if (pid == 0) {
    ::close(fd[0]);
    // What Gmsh (or a sanitizer, on a crash inside Gmsh) prints is not the user's: the outcome
    // goes back through the pipe.
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) {
      ::dup2(null, 1);
      ::dup2(null, 2);
    }
    std::string out;
    try {
      const RawMesh r = f();
      out = "M";
      put_vector(out, std::vector<double>(r.e.x.data(), r.e.x.data() + r.e.x.size()));
      put_vector(out, r.e.tets);
      put_groups(out, r.zones);
      put_groups(out, r.sets);
      put_fields(out, r.fields);
    } catch (const Error& e) {
      out = std::string("E") + e.what();
    } catch (const std::exception& e) {
      out = "E" + what + ": " + expected + " (" + e.what() + ")";
    }
    for (std::size_t at = 0; at < out.size();) {
      const ssize_t n = ::write(fd[1], out.data() + at, out.size() - at);
      if (n <= 0) _exit(2);
      at += static_cast<std::size_t>(n);
    }
    _exit(0);
  }
  ::close(fd[1]);
  std::string in;
  char buf[65536];
  for (ssize_t n; (n = ::read(fd[0], buf, sizeof buf)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    in.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status))
    throw Error(what + ": " + expected + " (Gmsh crashed on it: signal " + std::to_string(WTERMSIG(status)) + ")");
  if (in.empty() || (in[0] != 'M' && in[0] != 'E') || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw Error(what + ": " + expected + " (Gmsh crashed on it: exit status " +
                std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
  if (in[0] == 'E') throw Error(in.substr(1));
  Reader r{in, 1};
  RawMesh m;
  const std::vector<double> x = r.get_vector<double>();
  m.e.x = Eigen::Map<const Points>(x.data(), 3, static_cast<Eigen::Index>(x.size() / 3));
  m.e.tets = r.get_vector<Tet>();
  m.zones = r.get_groups();
  m.sets = r.get_groups();
  m.fields = r.get_fields();
  return m;
}

// Gmsh signals some failures by throwing non-standard values: turn anything but our own Error
// into one naming `what` and Gmsh's first logged error.
template <class F>
auto guarded(const std::string& what, const std::string& expected, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const Error&) {
    throw;
  } catch (...) {
    std::string err = GmshSession::first_error();
    throw Error(what + ": " + expected + (err.empty() ? "" : " (Gmsh: " + err + ")"));
  }
}

// Meshes the model's volumes; a failure, logged or thrown (Gmsh's TetGen throws a string on
// overlapping facets, found by the fuzzer on a sphere of radius 4.3e9), becomes an Error.
void generate_3d(const std::string& what) {
  guarded(what, "Gmsh could not mesh the volume", [] { gmsh::model::mesh::generate(3); });
  std::string err = GmshSession::first_error();
  if (!err.empty()) throw Error(what + ": Gmsh could not mesh the volume: " + err);
}

void check_readable(const std::string& path, const std::string& expected, double max_bytes) {
  check_input_file(path, expected, max_bytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot be read (expected " + expected + ")");
}

// The model's element data views (a .msh file's $ElementData, first step) on its tets, by view name.
std::map<std::string, Mesh::TetField> tet_fields(const Extracted& e, const std::string& what) {
  std::map<std::string, Mesh::TetField> fields;
  std::vector<int> views;
  gmsh::view::getTags(views);
  for (int v : views) {
    std::string type, name;
    std::vector<std::size_t> tags;
    std::vector<std::vector<double>> data;
    double time = 0;
    int components = 0;
    gmsh::view::getModelData(v, 0, type, tags, data, time, components);
    if (type != "ElementData" || components <= 0) continue;
    gmsh::option::getString("View[" + std::to_string(gmsh::view::getIndex(v)) + "].Name", name);
    Mesh::TetField& f = fields[name];
    if (f.components) throw Error(what + ": holds two element data views named \"" + name + "\"");
    f.components = components;
    f.values.assign(e.tets.size() * static_cast<std::size_t>(components), std::nan(""));
    for (std::size_t i = 0; i < tags.size(); ++i) {
      const auto it = e.tet_index.find(tags[i]);
      if (it == e.tet_index.end()) continue;  // data on elements that are not tets
      if (data[i].size() != static_cast<std::size_t>(components))
        throw Error(what + ": element data \"" + name + "\" gives element " + std::to_string(tags[i]) + " " +
                    std::to_string(data[i].size()) + " values, expected " + std::to_string(components));
      std::copy(data[i].begin(), data[i].end(), f.values.begin() + static_cast<long>(it->second) * components);
    }
  }
  return fields;
}

// The model's tets with its physical groups: 3-D groups become zones, groups of any dimension
// node sets (an unnamed group is physical_<dim>d_<tag>); and its element data on the tets.
RawMesh with_physical_groups(Extracted e, const std::string& what) {
  std::map<std::string, std::vector<int>> zones, sets;
  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups, -1);
  for (const auto& [dim, tag] : groups) {
    std::string name;
    gmsh::model::getPhysicalName(dim, tag, name);
    if (name.empty()) name = "physical_" + std::to_string(dim) + "d_" + std::to_string(tag);
    std::vector<std::size_t> ntags;
    std::vector<double> coord;
    gmsh::model::mesh::getNodesForPhysicalGroup(dim, tag, ntags, coord);
    auto& set = sets[name];
    for (std::size_t t : ntags) set.push_back(e.node_index.at(t));
    if (dim == 3) {
      std::vector<int> entities;
      gmsh::model::getEntitiesForPhysicalGroup(dim, tag, entities);
      auto& zone = zones[name];
      for (int ent : entities) {
        std::vector<std::size_t> etags, enodes;
        gmsh::model::mesh::getElementsByType(4, etags, enodes, ent);
        for (std::size_t t : etags) zone.push_back(e.tet_index.at(t));
      }
    }
  }
  std::map<std::string, Mesh::TetField> fields = tet_fields(e, what);
  return RawMesh{std::move(e), std::move(zones), std::move(sets), std::move(fields)};
}

}  // namespace

Mesh make_sphere(double radius, double edge_length, long target_tets, const Eigen::Vector3d& c, double inner_radius) {
  GmshSession session("sphere");
  const int outer = gmsh::model::occ::addSphere(c.x(), c.y(), c.z(), radius);
  if (inner_radius > 0) {
    const int inner = gmsh::model::occ::addSphere(c.x(), c.y(), c.z(), inner_radius);
    std::vector<std::pair<int, int>> out;
    std::vector<std::vector<std::pair<int, int>>> map;
    gmsh::model::occ::cut({{3, outer}}, {{3, inner}}, out, map);
  }
  gmsh::model::occ::synchronize();
  auto mesh_with = [&](double h) {
    gmsh::model::mesh::clear();
    gmsh::option::setNumber("Mesh.MeshSizeMin", h);
    gmsh::option::setNumber("Mesh.MeshSizeMax", h);
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
    generate_3d("sphere");
    std::vector<std::size_t> t, n;
    gmsh::model::mesh::getElementsByType(4, t, n);
    return static_cast<double>(t.size());
  };
  if (edge_length > 0) {
    mesh_with(edge_length);
  } else {
    // A Delaunay mesh has about 6 sqrt(2) V / h^3 tets; correct the estimate twice by the count.
    const double V = 4.0 / 3.0 * M_PI * (radius * radius * radius - inner_radius * inner_radius * inner_radius);
    // The count is not monotonic in h (Delaunay noise of several %): bracket the target and
    // interpolate in log-log within the bracket; keep the closest, stop within 2%.
    const double target = static_cast<double>(target_tets);
    double h = std::cbrt(6.0 * std::sqrt(2.0) * V / target), best_h = h, best_err = 1e300;
    double lo = 0, n_lo = 0, hi = 0, n_hi = 0;  // lo: h with too many tets, hi: too few
    for (int pass = 0; pass < 8; ++pass) {
      const double n = mesh_with(h);
      const double err = std::abs(n / target - 1.0);
      if (err < best_err) {
        best_err = err;
        best_h = h;
      }
      if (err < 0.02) break;
      if (n > target && (lo == 0 || h > lo)) lo = h, n_lo = n;
      if (n < target && (hi == 0 || h < hi)) hi = h, n_hi = n;
      if (lo > 0 && hi > 0) {
        const double s = std::log(target / n_lo) / std::log(n_hi / n_lo);  // in [0, 1]
        h = lo * std::pow(hi / lo, std::clamp(s, 0.1, 0.9));
      } else {
        h *= std::cbrt(n / target);
      }
    }
    if (best_h != h) mesh_with(best_h);
  }
  Extracted e = extract_tets("sphere");
  std::map<std::string, std::vector<int>> sets;
  if (inner_radius > 0) {
    const double tol = 1e-6 * radius;  // the walls' nodes lie on the spheres (Gmsh's OCC surfaces)
    for (int i = 0; i < e.x.cols(); ++i) {
      const double r = (e.x.col(i) - c).norm();
      if (std::abs(r - inner_radius) < tol) sets["inner"].push_back(i);
      if (std::abs(r - radius) < tol) sets["outer"].push_back(i);
    }
  }
  return finish(std::move(e), "sphere", {}, std::move(sets));
}

Mesh make_cylinder(double radius, double height, int resolution, const Eigen::Vector3d& c) {
  GmshSession session("cylinder");
  gmsh::model::occ::addCylinder(c.x(), c.y(), c.z() - height / 2, 0, 0, height, radius);
  gmsh::model::occ::synchronize();
  const double h = 2.0 * M_PI * radius / resolution;
  gmsh::option::setNumber("Mesh.MeshSizeMin", h);
  gmsh::option::setNumber("Mesh.MeshSizeMax", h);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
  generate_3d("cylinder");
  Extracted e = extract_tets("cylinder");
  std::map<std::string, std::vector<int>> sets;
  const double tol = 1e-9 * std::max(radius, height);
  for (int i = 0; i < e.x.cols(); ++i) {
    if (std::abs(e.x(2, i) - (c.z() - height / 2)) < tol) sets["bottom"].push_back(i);
    if (std::abs(e.x(2, i) - (c.z() + height / 2)) < tol) sets["top"].push_back(i);
  }
  return finish(std::move(e), "cylinder", {}, std::move(sets));
}

Mesh make_capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, double edge_length) {
  GmshSession session("capsule");
  const Eigen::Vector3d d = b - a;
  std::vector<std::pair<int, int>> parts = {{3, gmsh::model::occ::addSphere(a.x(), a.y(), a.z(), radius)},
                                            {3, gmsh::model::occ::addSphere(b.x(), b.y(), b.z(), radius)}};
  std::vector<std::pair<int, int>> tool = {
      {3, gmsh::model::occ::addCylinder(a.x(), a.y(), a.z(), d.x(), d.y(), d.z(), radius)}};
  std::vector<std::pair<int, int>> out;
  std::vector<std::vector<std::pair<int, int>>> map;
  gmsh::model::occ::fuse(parts, tool, out, map);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMin", edge_length);
  gmsh::option::setNumber("Mesh.MeshSizeMax", edge_length);
  gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
  generate_3d("capsule");
  return finish(extract_tets("capsule"), "capsule", {}, {});
}

namespace {
RawMesh read_msh_raw(const std::string& path) {
  check_readable(path, "a Gmsh .msh file", input_limits::kMesh);
  // Gmsh 4.8 falls back to its .geo parser on a file that is not a mesh, and a syntax error there
  // leaves Gmsh locked ("I'm busy!"): every later mesh of the process comes out empty. So the
  // header is checked here first; binary and ASCII .msh files both begin with $MeshFormat.
  {
    std::ifstream in(path, std::ios::binary);
    std::string first;
    std::getline(in, first);
    if (first.rfind("$MeshFormat", 0) != 0)
      throw Error(path +
                  ": is not a readable Gmsh mesh (expected a .msh file, version 2 or 4, starting with $MeshFormat)");
  }
  const std::string expected = "is not a readable Gmsh mesh (expected a .msh file, version 2 or 4)";
  return in_child(path, expected, [&] {
    GmshSession session("file");
    return guarded(path, expected, [&] {
      gmsh::open(path);
      std::string err = GmshSession::first_error();
      if (!err.empty()) throw Error(path + ": is not a readable Gmsh mesh: " + err);
      return with_physical_groups(extract_tets(path), path);
    });
  });
}
}  // namespace

Mesh read_msh(const std::string& path) { return finish(read_msh_raw(path), path); }

namespace {
// Opens a .geo script with `parameters` defined before it: Gmsh 4.8's API cannot set a parser
// variable, so they are written as a script of assignments that is opened first, and the script
// merged after it (a DefineConstant leaves a variable that exists as it is).
void open_geo(const std::string& path, const std::vector<std::pair<std::string, double>>& parameters) {
  if (parameters.empty()) return gmsh::open(path);
  std::string text;
  char line[256];
  for (const auto& [name, value] : parameters) {
    std::snprintf(line, sizeof line, " = %.17g;\n", value);
    text += name + line;
  }
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::temp_directory_path(ec);
  if (ec)
    throw Error(path + ": its parameters are written to a temporary script, and there is no temporary directory (" +
                ec.message() + "; expected TMPDIR to name a directory)");
  std::string temp = (dir / "isochor-geo-XXXXXX.geo").string();
  const int fd = mkstemps(temp.data(), 4);
  if (fd < 0) throw Error(path + ": could not write the parameters' script in " + temp + ": " + std::strerror(errno));
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  struct Remove {
    std::string p;
    ~Remove() { std::remove(p.c_str()); }
  } remove{temp};
  if (!written) throw Error(path + ": could not write the parameters' script " + temp);
  gmsh::open(temp);
  gmsh::merge(path);
}
}  // namespace

namespace {
// A lower bound on the tets Gmsh will make of the open model, from its 1-D mesh alone (cheap where
// the 3-D mesh would not be): each surface's area is at least its boundary loops' vector area
// (exact for a plane), its triangles at most equilateral of 1.5 times the longest 1-D element,
// and a tet has at most 4 faces on surfaces.
double geo_tets_at_least(std::size_t* curve_elements = nullptr) {
  gmsh::model::mesh::generate(1);
  if (curve_elements) {
    std::vector<std::size_t> etags, enodes;
    gmsh::model::mesh::getElementsByType(1, etags, enodes);
    *curve_elements = etags.size();
  }
  std::vector<std::size_t> ntags;
  std::vector<double> xyz, param;
  gmsh::model::mesh::getNodes(ntags, xyz, param, -1, -1, true, false);
  std::unordered_map<std::size_t, Eigen::Vector3d> at;
  for (std::size_t k = 0; k < ntags.size(); ++k)
    at[ntags[k]] = Eigen::Vector3d(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
  double longest = 0, triangles = 0;
  gmsh::vectorpair surfaces;
  gmsh::model::getEntities(surfaces, 2);
  for (const auto& surface : surfaces) {
    gmsh::vectorpair curves;
    gmsh::model::getBoundary({surface}, curves, false, true, false);
    Eigen::Vector3d area = Eigen::Vector3d::Zero();
    for (const auto& [dim, signed_tag] : curves) {
      std::vector<std::size_t> etags, enodes;
      gmsh::model::mesh::getElementsByType(1, etags, enodes, std::abs(signed_tag));
      for (std::size_t e = 0; e + 1 < enodes.size(); e += 2) {
        const Eigen::Vector3d& a = at[enodes[e]];
        const Eigen::Vector3d& b = at[enodes[e + 1]];
        longest = std::max(longest, (b - a).norm());
        area += (signed_tag < 0 ? -0.5 : 0.5) * a.cross(b);
      }
    }
    triangles += area.norm();
  }
  if (longest <= 0) return 0;
  const double h = 1.5 * longest;
  return triangles / (std::sqrt(3.0) / 4 * h * h) / 4;
}

// The same estimate from a 1-D mesh at kProbeFactor times the script's sizes, for scripts whose
// 1-D mesh alone would not fit (cook.geo at N = 1e7: 26 s and 5.5 GB before Gmsh aborted): where
// that mesh scaled back holds more than kProbeCurveElements elements, the bound scaled back by
// kProbeFactor^2 (the triangles go as 1/h^2), a tenth of it to stay below the true one where
// sizes are clamped; otherwise 0 (the script's own 1-D mesh is cheap: geo_tets_at_least decides).
double geo_tets_probe() {
  constexpr double kProbeFactor = 100, kProbeCurveElements = 1e6;
  double factor = 1;
  gmsh::option::getNumber("Mesh.MeshSizeFactor", factor);
  gmsh::option::setNumber("Mesh.MeshSizeFactor", factor * kProbeFactor);
  std::size_t curve_elements = 0;
  const double coarse = geo_tets_at_least(&curve_elements);
  gmsh::model::mesh::clear();
  gmsh::option::setNumber("Mesh.MeshSizeFactor", factor);
  if (static_cast<double>(curve_elements) * kProbeFactor <= kProbeCurveElements) return 0;
  return coarse * kProbeFactor * kProbeFactor / 10;
}
}  // namespace

Mesh read_geo(const std::string& path, double edge_length,
              const std::vector<std::pair<std::string, double>>& parameters,
              const std::function<void(double)>& check_tets) {
  check_readable(path, "a Gmsh .geo script", input_limits::kScene);
  const std::string expected = "Gmsh could not read or mesh the .geo script";
  // In a child process: a syntax error leaves Gmsh locked for the rest of the process (read_msh).
  RawMesh raw = in_child(path, expected, [&] {
    GmshSession session("geo");
    return guarded(path, expected, [&] {
      if (edge_length > 0) {
        gmsh::option::setNumber("Mesh.MeshSizeMin", edge_length);
        gmsh::option::setNumber("Mesh.MeshSizeMax", edge_length);
        gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
      }
      open_geo(path, parameters);
      std::string err = GmshSession::first_error();
      if (!err.empty()) throw Error(path + ": is not a readable .geo script: " + err);
      // A script that meshes itself (Mesh 3;) leaves tets; otherwise its volumes are meshed here.
      std::vector<std::size_t> t, n;
      gmsh::model::mesh::getElementsByType(4, t, n);
      if (t.empty()) {
        gmsh::vectorpair volumes;
        gmsh::model::getEntities(volumes, 3);
        if (volumes.empty()) throw Error(path + ": the script defines no volume (expected a 3-D geometry)");
        if (check_tets) {
          if (const double probe = geo_tets_probe(); probe > 0) check_tets(probe);
          check_tets(geo_tets_at_least());
        }
        generate_3d(path);
      }
      return with_physical_groups(extract_tets(path), path);
    });
  });
  return finish(std::move(raw), path);
}

namespace {

// A private directory under the system's temporary one, removed with what it holds.
class TempDir {
 public:
  explicit TempDir(const std::string& what) {
    std::error_code ec;
    std::string t = (std::filesystem::temp_directory_path(ec) / "isochor-fill-XXXXXX").string();
    if (ec || !::mkdtemp(t.data()))
      throw Error(what + ": cannot make a temporary directory for Gmsh (" +
                  (ec ? ec.message() : std::string(std::strerror(errno))) + "; TMPDIR names where)");
    path_ = t;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const char* name) const { return (std::filesystem::path(path_) / name).string(); }

 private:
  std::string path_;
};

// The surface as a Gmsh 2.2 .msh file (every coordinate to the last bit), and the script that
// fills it: Gmsh's Delaunay on the surface nodes alone, or HXT refining inside to `edge_length`.
void write_fill_input(const TempDir& dir, const Points& x, const std::vector<Tri>& tris, double edge_length,
                      const std::string& what) {
  const std::string surface = dir.file("surface.msh"), script = dir.file("fill.geo");
  std::FILE* f = std::fopen(surface.c_str(), "w");
  bool ok = f && std::fprintf(f, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%ld\n", long(x.cols())) > 0;
  for (Eigen::Index i = 0; ok && i < x.cols(); ++i)
    ok = std::fprintf(f, "%ld %.17g %.17g %.17g\n", long(i + 1), x(0, i), x(1, i), x(2, i)) > 0;
  ok = ok && std::fprintf(f, "$EndNodes\n$Elements\n%zu\n", tris.size()) > 0;
  for (std::size_t t = 0; ok && t < tris.size(); ++t)
    ok = std::fprintf(f, "%zu 2 2 0 1 %d %d %d\n", t + 1, tris[t][0] + 1, tris[t][1] + 1, tris[t][2] + 1) > 0;
  ok = ok && std::fprintf(f, "$EndElements\n") > 0;
  if (f) ok = std::fclose(f) == 0 && ok;
  std::string text = "General.NumThreads = 1;\nMesh.RandomSeed = 1;\n";
  char line[160];
  if (edge_length > 0) {
    // Gmsh 4.8's Delaunay does not refine inside a discrete surface; HXT does, by the size
    // bound. The surface triangles stay as they are.
    std::snprintf(line, sizeof line, "Mesh.Algorithm3D = 10;\nMesh.MeshSizeMax = %.17g;\n", edge_length);
    text += std::string(line) + "Mesh.MeshSizeExtendFromBoundary = 0;\nMesh.MeshSizeFromPoints = 0;\n";
  } else {
    text += "Mesh.Algorithm3D = 1;\n";
  }
  text += "Merge \"" + surface + "\";\nSurface Loop(1) = {1};\nVolume(1) = {1};\nMesh 3;\nSave \"" +
          dir.file("volume.msh") + "\";\n";
  std::ofstream g(script);
  g << text;
  g.close();
  if (!ok || !g)
    throw Error(what + ": cannot write Gmsh's input into " + surface + " (" + std::strerror(errno) +
                "; the temporary directory must have room)");
}

// Runs Gmsh's program on the script, its messages into the log; its wait status.
int run_gmsh(const TempDir& dir, const std::string& what) {
  // Gmsh's program reads the user's ~/.gmshrc and ~/.gmsh-options, which may set mesh options
  // (a Mesh.MeshSizeFactor there took the torso from 3,702 to 16,886 nodes): its HOME is the
  // empty temporary directory.
  pid_t pid = 0;
  const int rc = spawn_logged(
      {"gmsh", "-nopopup", "-v", "1", dir.file("fill.geo"), "-"}, dir.file("gmsh.log"),
      [](const std::string& v) { return v.rfind("HOME=", 0) == 0; }, {"HOME=" + dir.file("")}, pid);
  if (rc != 0)
    throw Error(what + ": cannot run Gmsh's program gmsh to fill the surface with tets (" + std::strerror(rc) +
                "; it comes with Debian's package gmsh)");
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

// Fills a closed, outward surface with tets by Gmsh's own program in a new process. Gmsh's HXT
// fill inside this process (a forked child) came out different with the process's heap history:
// the same character scene gave meshes of 8,027 to 8,048 nodes as --set keys were added, and
// differed between builds and thread counts. A new process starts from the same state each time.
Mesh fill_in_gmsh_process(const Points& x, const std::vector<Tri>& tris, double edge_length, const std::string& what) {
  const TempDir dir(what);
  write_fill_input(dir, x, tris, edge_length, what);
  const int status = run_gmsh(dir, what);
  std::ifstream log(dir.file("gmsh.log"));
  std::string error;
  for (std::string l; error.empty() && std::getline(log, l);)
    if (l.rfind("Error", 0) == 0) error = l.substr(std::min(l.size(), l.find(':') + 2));
  const std::string expected = "Gmsh could not tetrahedralise the surface";
  if (WIFSIGNALED(status))
    throw Error(what + ": " + expected + " (Gmsh crashed on it: signal " + std::to_string(WTERMSIG(status)) + ")");
  if (!error.empty() || !WIFEXITED(status) || WEXITSTATUS(status) != 0 ||
      !std::filesystem::exists(dir.file("volume.msh")))
    throw Error(
        what + ": " + expected +
        (error.empty() ? " (gmsh exit status " + std::to_string(WEXITSTATUS(status)) + ")" : " (Gmsh: " + error + ")"));
  try {
    return finish(read_msh_raw(dir.file("volume.msh")), what);
  } catch (const Error& e) {
    throw Error(what + ": " + expected + " (its output: " + e.what() + ")");
  }
}

}  // namespace

Mesh mesh_closed_surface(const std::string& path, double edge_length) {
  check_readable(path, "a closed triangle surface (.obj or .stl)", input_limits::kSurface);
  Points x;
  std::vector<Tri> tris;
  read_surface(path, x, tris);
  return mesh_closed_surface(x, std::move(tris), edge_length, path);
}

Mesh mesh_closed_surface(const Points& x, std::vector<Tri> tris, double edge_length, const std::string& path) {
  if (tris.empty()) throw Error(path + ": has no triangles (expected a closed surface)");
  SurfaceCheck sc = check_surface(tris);
  if (!sc.closed)
    throw Error(path + ": the surface is not closed: edge (" + std::to_string(sc.first_bad_edge[0] + 1) + ", " +
                std::to_string(sc.first_bad_edge[1] + 1) + ") is in " +
                (sc.boundary_edges ? "one triangle" : "more than two triangles") +
                ", expected every edge in exactly two (" + std::to_string(sc.boundary_edges) + " boundary, " +
                std::to_string(sc.nonmanifold_edges) + " non-manifold edges)");
  if (!sc.oriented)
    throw Error(path + ": the triangles are not consistently oriented (expected every edge traversed once each way)");
  double vol = surface_volume(x, tris);
  if (vol < 0) {  // inward: flip
    for (Tri& t : tris) std::swap(t[1], t[2]);
  }
  return fill_in_gmsh_process(x, tris, edge_length, path);
}

}  // namespace isochor
