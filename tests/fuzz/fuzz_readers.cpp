// isochor_fuzz READER ITERATIONS SEED OUT_DIR [SEED_FILE...]: a deterministic fuzzer of isochor's
// readers. Each iteration takes a seed input, mutates its bytes and structure (bit
// flips, interesting bytes, deleted, duplicated and swapped ranges and lines, numbers replaced by
// extreme values, truncation; for scenes also --set overrides with extreme values), writes it to
// OUT_DIR and reads it. A reader may refuse its input only with isochor::Error (the one-line
// message the command line prints); anything else fails the run: another exception, a crash (the
// sanitizers abort), or an input that takes more than 10 s (SIGALRM). The input at fault stays in
// OUT_DIR/failure.* and its path is printed, to become a regression input in tests/data/fuzz/.
//
// Readers: scene (TOML, with overrides; meshing included, within a 200 MB budget), msh (Gmsh
// v2.2 and v4.1), tetgen (.node/.ele), obj, stl (closed surfaces, read only), bvh, gltf (a rigged
// character, .glb or .gltf), ply and csv (paint files, carried onto a small box). The msh, ply,
// csv, tetgen, obj and stl seeds are made here (a small Gmsh mesh of two boxes, written in each
// format); scene, bvh and gltf seeds are given as files.
#include <gmsh.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "isochor/core/bvh.hpp"
#include "isochor/core/gltf.hpp"
#include "isochor/base/error.hpp"
#include "isochor/core/memory.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/core/paint.hpp"
#include "isochor/scene/scene.hpp"

using namespace isochor;
namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// The input being read, for the alarm handler (async-signal-safe output only).
char g_current[4096] = {0};
void on_alarm(int) {
  const char msg[] = "isochor_fuzz: HANG (over 10 s) on ";
  [[maybe_unused]] ssize_t n = write(2, msg, sizeof msg - 1);
  n = write(2, g_current, std::strlen(g_current));
  n = write(2, "\n", 1);
  _exit(3);
}

const char* const kNumbers[] = {
    "0",      "-1",  "1e308", "-1e308",    "nan", "inf", "-inf",       "2147483648",          "9223372036854775807",
    "1e-300", "0.5", "3",     "100000000", "-0",  "1e9", "4294967296", "18446744073709551616"};
const char kBytes[] = "0-9.e\n \t[]\"={}$,#'\\";

class Mutator {
 public:
  explicit Mutator(unsigned long seed) : rng_(seed) {}
  std::size_t below(std::size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng_); }

  std::string mutate(std::string s) {
    const int count = 1 + static_cast<int>(below(3));
    for (int i = 0; i < count; ++i) s = once(std::move(s));
    return s;
  }

 private:
  std::string once(std::string s) {
    if (s.empty()) return std::string(1, kBytes[below(sizeof kBytes - 1)]);
    switch (below(9)) {
      case 0:
        s[below(s.size())] ^= static_cast<char>(1u << below(8));
        break;
      case 1:
        s[below(s.size())] = kBytes[below(sizeof kBytes - 1)];
        break;
      case 2: {
        const std::size_t at = below(s.size());
        s.erase(at, 1 + below(16));
        break;
      }
      case 3: {
        const std::size_t at = below(s.size()), len = 1 + below(64);
        s.insert(below(s.size()), s.substr(at, len));
        break;
      }
      case 4:
        return number(std::move(s));
      case 5:
        return lines(std::move(s), 0);
      case 6:
        return lines(std::move(s), 1);
      case 7:
        return lines(std::move(s), 2);
      default:
        s.resize(below(s.size()));
        break;
    }
    return s;
  }

  // A number of the text replaced by an extreme one.
  std::string number(std::string s) {
    static const std::regex re("[-+]?[0-9]+(\\.[0-9]*)?([eE][-+]?[0-9]+)?");
    std::vector<std::pair<std::size_t, std::size_t>> at;
    for (auto it = std::sregex_iterator(s.begin(), s.end(), re); it != std::sregex_iterator() && at.size() < 4096; ++it)
      at.emplace_back(static_cast<std::size_t>(it->position()), static_cast<std::size_t>(it->length()));
    if (at.empty()) return s;
    const auto [pos, len] = at[below(at.size())];
    return s.replace(pos, len, kNumbers[below(std::size(kNumbers))]);
  }

  // Lines deleted (0), duplicated (1) or swapped (2).
  std::string lines(const std::string& s, int kind) {
    std::vector<std::string> l;
    std::istringstream in(s);
    for (std::string line; std::getline(in, line);) l.push_back(line);
    if (l.empty()) return s;
    const std::size_t a = below(l.size()), b = below(l.size());
    if (kind == 0)
      l.erase(l.begin() + static_cast<long>(a));
    else if (kind == 1)
      l.insert(l.begin() + static_cast<long>(b), l[a]);
    else
      std::swap(l[a], l[b]);
    std::string out;
    for (const std::string& line : l) out += line + "\n";
    return out;
  }

  std::mt19937_64 rng_;
};

// Seeds for the mesh readers: two boxes sharing a face, meshed by Gmsh and written in each format.
std::vector<fs::path> make_mesh_seeds(const std::string& reader, const fs::path& dir) {
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  gmsh::model::add("seed");
  gmsh::model::occ::addBox(0, 0, 0, 1, 1, 1);
  gmsh::model::occ::addBox(1, 0, 0, 1, 1, 1);
  std::vector<std::pair<int, int>> out;
  std::vector<std::vector<std::pair<int, int>>> map;
  gmsh::model::occ::fragment({{3, 1}}, {{3, 2}}, out, map);
  gmsh::model::occ::synchronize();
  gmsh::model::addPhysicalGroup(3, {1}, 1);
  gmsh::model::setPhysicalName(3, 1, "left");
  gmsh::model::addPhysicalGroup(2, {1}, 2);
  gmsh::model::setPhysicalName(2, 2, "face");
  gmsh::option::setNumber("Mesh.MeshSizeMax", 0.5);
  gmsh::model::mesh::generate(3);
  std::vector<fs::path> seeds;
  if (reader == "msh") {
    for (const auto& [version, name] : {std::pair{2.2, "v22.msh"}, std::pair{4.1, "v41.msh"}}) {
      gmsh::option::setNumber("Mesh.MshFileVersion", version);
      gmsh::write((dir / name).string());
      seeds.push_back(dir / name);
    }
  } else if (reader == "stl") {
    gmsh::write((dir / "seed.stl").string());
    seeds.push_back(dir / "seed.stl");
  }
  gmsh::finalize();
  if (reader == "ply" || reader == "csv") {  // paint files: ASCII and binary PLY, CSV by point and by node
    const Mesh m = make_box({1, 1, 1}, {2, 2, 2}, Eigen::Vector3d::Zero(), 6);
    std::ostringstream ascii, binary, points, nodes;
    const char* header =
        "element vertex %d\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
        "property uchar green\nproperty uchar blue\nproperty int label\nelement face %d\n"
        "property list uchar int vertex_indices\nend_header\n";
    char h[400];
    std::snprintf(h, sizeof h, header, m.num_nodes(), static_cast<int>(m.surface().size()));
    ascii << "ply\nformat ascii 1.0\n" << h;
    binary << "ply\nformat binary_little_endian 1.0\n" << h;
    points << "x,y,z,label,w\n";
    nodes << "node,label\n";
    for (int i = 0; i < m.num_nodes(); ++i) {
      const Eigen::Vector3d p = m.rest_positions().col(i);
      ascii << p.x() << " " << p.y() << " " << p.z() << " 255 0 " << i % 256 << " " << i % 3 << "\n";
      const float f[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
      const unsigned char c[3] = {255, 0, static_cast<unsigned char>(i % 256)};
      const int label = i % 3;
      binary.write(reinterpret_cast<const char*>(f), sizeof f);
      binary.write(reinterpret_cast<const char*>(c), sizeof c);
      binary.write(reinterpret_cast<const char*>(&label), sizeof label);
      points << p.x() << "," << p.y() << "," << p.z() << "," << i % 3 << "," << 0.1 * (i % 10) << "\n";
      nodes << i << "," << i % 3 << "\n";
    }
    for (const Tri& t : m.surface()) {
      ascii << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
      const unsigned char three = 3;
      binary.write(reinterpret_cast<const char*>(&three), 1);
      binary.write(reinterpret_cast<const char*>(t.data()), 3 * sizeof(int));
    }
    if (reader == "ply") {
      write_text(dir / "ascii.ply", ascii.str());
      write_text(dir / "binary.ply", binary.str());
      seeds.push_back(dir / "ascii.ply");
      seeds.push_back(dir / "binary.ply");
    } else {
      write_text(dir / "points.csv", points.str());
      write_text(dir / "nodes.csv", nodes.str());
      seeds.push_back(dir / "points.csv");
      seeds.push_back(dir / "nodes.csv");
    }
  }
  if (reader == "tetgen" || reader == "obj") {
    const Mesh m = make_box({1, 1, 1}, {2, 2, 2}, Eigen::Vector3d::Zero(), 6);
    std::ostringstream node, ele, obj;
    node << m.num_nodes() << " 3 0 0\n";
    for (int i = 0; i < m.num_nodes(); ++i)
      node << i + 1 << " " << m.rest_positions()(0, i) << " " << m.rest_positions()(1, i) << " "
           << m.rest_positions()(2, i) << "\n";
    ele << m.num_tets() << " 4 1\n";
    for (int e = 0; e < m.num_tets(); ++e)
      ele << e + 1 << " " << m.tets()[e][0] + 1 << " " << m.tets()[e][1] + 1 << " " << m.tets()[e][2] + 1 << " "
          << m.tets()[e][3] + 1 << " " << (e % 2) << "\n";
    for (int i = 0; i < m.num_nodes(); ++i)
      obj << "v " << m.rest_positions()(0, i) << " " << m.rest_positions()(1, i) << " " << m.rest_positions()(2, i)
          << "\n";
    for (const Tri& t : m.surface()) obj << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
    if (reader == "tetgen") {
      write_text(dir / "seed.node", node.str());
      write_text(dir / "seed.ele", ele.str());
      seeds.push_back(dir / "seed.node");
      seeds.push_back(dir / "seed.ele");
    } else {
      write_text(dir / "seed.obj", obj.str());
      seeds.push_back(dir / "seed.obj");
    }
  }
  return seeds;
}

// Reads one input with the reader; isochor::Error is the reader refusing it (fine).
void read_input(const std::string& reader, const fs::path& p, const std::vector<std::string>& overrides) {
  Points x;
  std::vector<Tri> tris;
  if (reader == "scene")
    (void)load_scene(p.string(), overrides);
  else if (reader == "msh")
    (void)read_msh(p.string());
  else if (reader == "tetgen")
    (void)read_tetgen(p.string());
  else if (reader == "obj")
    read_obj_surface(p.string(), x, tris);
  else if (reader == "stl")
    read_stl_surface(p.string(), x, tris);
  else if (reader == "bvh")
    (void)read_bvh(p.string());
  else if (reader == "gltf")
    (void)read_gltf(p.string());
  else if (reader == "ply" || reader == "csv") {  // paint files, read against a 27-node mesh
    const Mesh m = make_box({1, 1, 1}, {2, 2, 2}, Eigen::Vector3d::Zero(), 6);
    const PaintedPoints painted = read_paint(p.string(), &m.rest_positions());
    PaintRule rule;
    rule.zones = {"a", "b"};
    rule.labels = {1, 2};
    (void)painted_zones(m, painted, paint_membership(painted, rule), 1e9);
  } else
    throw std::invalid_argument("unknown reader " + reader);
}

// --set overrides for a scene: keys of the seed (key = value lines, under their [table]) with
// extreme or mutated values.
std::vector<std::string> overrides_for(const std::string& text, Mutator& m) {
  std::vector<std::string> keys;
  std::string table;
  std::istringstream in(text);
  static const std::regex header("^\\s*\\[([A-Za-z_.]+)\\]\\s*$"), pair("^\\s*([A-Za-z_]+)\\s*=\\s*(.*)$");
  for (std::string line; std::getline(in, line);) {
    std::smatch s;
    if (std::regex_match(line, s, header))
      table = s[1];
    else if (std::regex_match(line, s, pair))
      keys.push_back((table.empty() ? "" : table + ".") + std::string(s[1]));
  }
  std::vector<std::string> out;
  if (keys.empty()) return out;
  const std::size_t n = m.below(3);
  for (std::size_t i = 0; i < n; ++i) {
    const std::string value = m.below(2) ? kNumbers[m.below(std::size(kNumbers))] : m.mutate("[1.0, 2.0, 3.0]");
    out.push_back(keys[m.below(keys.size())] + "=" + value);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: isochor_fuzz READER ITERATIONS SEED OUT_DIR [SEED_FILE...]\n");
    return 2;
  }
  const std::string reader = argv[1];
  const long iterations = std::stol(argv[2]);
  const unsigned long seed = std::stoul(argv[3]);
  const fs::path dir = argv[4];
  fs::create_directories(dir);
  std::vector<fs::path> seeds(argv + 5, argv + argc);
  if (seeds.empty()) seeds = make_mesh_seeds(reader, dir);
  if (seeds.empty()) {
    std::fprintf(stderr, "isochor_fuzz: no seeds for %s\n", reader.c_str());
    return 2;
  }
  // Scenes mesh what they ask for: a budget keeps a legitimately large mesh from being taken for
  // a hang (it is refused, naming the key).
  set_memory_budget_mb(200);
  std::signal(SIGALRM, on_alarm);  // (in each child: alarm(10) before its read)
  Mutator m(seed);
  long refused = 0;
  for (long i = 0; i < iterations; ++i) {
    const fs::path& from = seeds[static_cast<std::size_t>(i) % seeds.size()];
    const std::string text = read_text(from);
    // A .node/.ele pair: mutate one of the two, keep the other (read_tetgen opens both).
    const std::string ext = from.extension().string();
    const fs::path input = dir / ("input" + ext);
    if (reader == "tetgen") {
      for (const char* e : {".node", ".ele"})
        fs::copy_file(fs::path(from).replace_extension(e), dir / (std::string("input") + e),
                      fs::copy_options::overwrite_existing);
    }
    write_text(input, m.mutate(text));
    const std::vector<std::string> overrides =
        reader == "scene" && m.below(3) == 0 ? overrides_for(text, m) : std::vector<std::string>{};
    std::string label = input.string();
    for (const std::string& o : overrides) label += " --set '" + o + "'";
    std::snprintf(g_current, sizeof g_current, "%s (iteration %ld, from %s)", label.c_str(), i, from.string().c_str());
    // The input as it is now, kept as failure.* should the reader crash or hang.
    fs::copy_file(input, dir / ("failure" + ext), fs::copy_options::overwrite_existing);
    // Each input is read in a child process: a crash or a hang is the child's, and Gmsh's global
    // state (which one failed load can leave locked for the rest of a process) starts clean.
    std::fflush(nullptr);
    const pid_t pid = fork();
    if (pid == 0) {
      alarm(10);
      try {
        read_input(reader, input, overrides);
      } catch (const Error& e) {
        if (std::getenv("ISOCHOR_FUZZ_VERBOSE")) std::fprintf(stderr, "refused: %s\n", e.what());
        _exit(10);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "isochor_fuzz: %s: not an isochor::Error but %s: %s\n", g_current, typeid(e).name(),
                     e.what());
        _exit(1);
      }
      _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 10) {
      ++refused;
    } else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      if (WIFSIGNALED(status))
        std::fprintf(stderr, "isochor_fuzz: CRASH (signal %d) on %s\n", WTERMSIG(status), g_current);
      std::fprintf(stderr, "isochor_fuzz: the input is kept as %s\n", (dir / ("failure" + ext)).c_str());
      return 1;
    }
  }
  for (const fs::path& p : seeds) fs::remove(dir / ("failure" + p.extension().string()));
  std::printf("isochor_fuzz %s: %ld inputs (seed %lu), %ld refused with a one-line error, the rest read\n",
              reader.c_str(), iterations, seed, refused);
  return 0;
}
