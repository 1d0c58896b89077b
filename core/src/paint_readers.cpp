#include "isochor/core/csv.hpp"
#include "isochor/core/input_file.hpp"
#include "isochor/core/paint.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "isochor/base/error.hpp"

namespace isochor {

namespace {

// ---- PLY ------------------------------------------------------------------------------------

struct PlyProperty {
  std::string name, type, count_type;  // count_type: a list's
  bool list = false;
};
struct PlyElement {
  std::string name;
  long count = 0;
  std::vector<PlyProperty> props;
};

int ply_size(const std::string& t, const std::string& path) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  throw Error(path + ": unknown PLY property type \"" + t + "\"");
}

double ply_binary(const char* p, const std::string& t, bool swap, const std::string& path) {
  char b[8];
  const int n = ply_size(t, path);
  for (int i = 0; i < n; ++i) b[i] = swap ? p[n - 1 - i] : p[i];
  auto get = [&](auto v) {
    std::memcpy(&v, b, sizeof v);
    return static_cast<double>(v);
  };
  if (t == "char" || t == "int8") return get(std::int8_t{});
  if (t == "uchar" || t == "uint8") return get(std::uint8_t{});
  if (t == "short" || t == "int16") return get(std::int16_t{});
  if (t == "ushort" || t == "uint16") return get(std::uint16_t{});
  if (t == "int" || t == "int32") return get(std::int32_t{});
  if (t == "uint" || t == "uint32") return get(std::uint32_t{});
  if (t == "float" || t == "float32") return get(float{});
  return get(double{});
}

struct PlyHeader {
  std::string format;  // ascii, binary_little_endian or binary_big_endian
  std::vector<PlyElement> elements;
};

// One "property ..." line of the header (after its tag).
PlyProperty ply_property(std::istringstream& s, const std::string& path) {
  PlyProperty p;
  std::string t;
  s >> t;
  if (t == "list") {
    p.list = true;
    s >> p.count_type >> p.type >> p.name;
    ply_size(p.count_type, path);
  } else {
    p.type = t;
    s >> p.name;
  }
  ply_size(p.type, path);
  return p;
}

// The header, up to end_header (the stream is left at the data).
PlyHeader read_ply_header(std::istream& in, const std::string& path) {
  std::string line;
  long line_no = 0;
  auto fail = [&](const std::string& what) { throw Error(path + ":" + std::to_string(line_no) + ": " + what); };
  std::getline(in, line);
  ++line_no;
  if (line.rfind("ply", 0) != 0) fail("expected \"ply\" on the first line");
  PlyHeader h;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "format") {
      s >> h.format;
      if (h.format != "ascii" && h.format != "binary_little_endian" && h.format != "binary_big_endian")
        fail("unknown PLY format \"" + h.format + "\" (expected ascii, binary_little_endian or binary_big_endian)");
    } else if (tag == "element") {
      PlyElement e;
      if (!(s >> e.name >> e.count) || e.count < 0) fail("expected: element NAME COUNT");
      h.elements.push_back(e);
    } else if (tag == "property") {
      if (h.elements.empty()) fail("a property before any element");
      h.elements.back().props.push_back(ply_property(s, path));
      if (h.elements.back().props.back().name.empty()) fail("expected: property TYPE NAME");
    } else if (tag == "end_header") {
      break;
    } else if (tag != "comment" && tag != "obj_info" && !tag.empty()) {
      fail("unexpected \"" + tag + "\" in the PLY header");
    }
  }
  if (h.format.empty()) fail("no format line in the PLY header");
  return h;
}

// The data's values one at a time, as ASCII tokens or binary numbers of the given type.
class PlyValues {
 public:
  PlyValues(std::istream& in, const std::string& format, const std::string& path)
      : in_(in), path_(path), ascii_(format == "ascii"), swap_(format == "binary_big_endian") {
    // binary_big_endian is swapped: this machine is little-endian (x86-64, arm64).
    if (!ascii_) return;
    std::string rest((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::istringstream s(rest);
    for (std::string t; s >> t;) tokens_.push_back(t);
  }

  double next(const std::string& type) {
    if (ascii_) {
      if (next_ >= tokens_.size()) throw Error(path_ + ": the PLY data end before the header's elements");
      try {
        return std::stod(tokens_[next_++]);
      } catch (...) {
        throw Error(path_ + ": \"" + tokens_[next_ - 1] + "\" is not a number");
      }
    }
    char b[8];
    const int n = ply_size(type, path_);
    if (!in_.read(b, n)) throw Error(path_ + ": the PLY data end before the header's elements");
    return ply_binary(b, type, swap_, path_);
  }

 private:
  std::istream& in_;
  const std::string& path_;
  bool ascii_, swap_;
  std::vector<std::string> tokens_;
  std::size_t next_ = 0;
};

// One element's values, property by property (lists read and dropped).
std::vector<std::vector<double>> ply_columns(const PlyElement& e, PlyValues& values, const std::string& path) {
  std::vector<std::vector<double>> cols(e.props.size());
  for (long i = 0; i < e.count; ++i)
    for (std::size_t k = 0; k < e.props.size(); ++k) {
      const PlyProperty& p = e.props[k];
      if (!p.list) {
        cols[k].push_back(values.next(p.type));
        continue;
      }
      const double n = values.next(p.count_type);
      if (!(n >= 0 && n <= 1e6) || n != std::floor(n))
        throw Error(path + ": a PLY list of " + std::to_string(n) + " items");
      for (long j = 0; j < static_cast<long>(n); ++j) values.next(p.type);
    }
  return cols;
}

PaintedPoints read_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot be read (expected a PLY file)");
  const PlyHeader h = read_ply_header(in, path);
  PaintedPoints out;
  out.path = path;
  PlyValues values(in, h.format, path);
  // The elements before the vertices are read past; those after are not read.
  auto vertex =
      std::find_if(h.elements.begin(), h.elements.end(), [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex == h.elements.end()) throw Error(path + ": no vertex element in the PLY header");
  for (auto e = h.elements.begin(); e != vertex; ++e) ply_columns(*e, values, path);
  std::vector<std::vector<double>> cols = ply_columns(*vertex, values, path);
  for (std::size_t k = 0; k < vertex->props.size(); ++k) {
    const PlyProperty& p = vertex->props[k];
    if (p.list) continue;
    const bool colour = p.name == "red" || p.name == "green" || p.name == "blue" || p.name == "alpha";
    if (colour && (p.type == "uchar" || p.type == "uint8"))
      for (double& v : cols[k]) v /= 255.0;
    out.names.push_back(p.name);
    out.values.push_back(std::move(cols[k]));
  }
  const auto* x = out.find("x");
  const auto* y = out.find("y");
  const auto* z = out.find("z");
  if (!x || !y || !z) throw Error(path + ": the PLY vertices have no x, y, z properties");
  out.x.resize(3, static_cast<Eigen::Index>(x->size()));
  for (std::size_t i = 0; i < x->size(); ++i) out.x.col(i) = Eigen::Vector3d((*x)[i], (*y)[i], (*z)[i]);
  return out;
}

// ---- OBJ (v x y z [r g b]) and CSV ------------------------------------------------------------

PaintedPoints read_obj_paint(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot be read (expected an OBJ file)");
  PaintedPoints out;
  out.path = path;
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> rgb[3];
  std::string line;
  long line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream s(line);
    std::string tag;
    if (!(s >> tag) || tag != "v") continue;
    Eigen::Vector3d p;
    if (!(s >> p.x() >> p.y() >> p.z()) || !p.allFinite())
      throw Error(path + ":" + std::to_string(line_no) + ": expected a vertex: v x y z [r g b]");
    pts.push_back(p);
    double c[3];
    if (s >> c[0] >> c[1] >> c[2]) {
      if (rgb[0].size() + 1 != pts.size())
        throw Error(path + ":" + std::to_string(line_no) +
                    ": a vertex colour after vertices without one (expected every vertex coloured)");
      for (int k = 0; k < 3; ++k) rgb[k].push_back(c[k]);
    } else if (!rgb[0].empty()) {
      throw Error(path + ":" + std::to_string(line_no) +
                  ": a vertex without a colour after coloured ones (expected v x y z r g b)");
    }
  }
  out.x.resize(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i) out.x.col(i) = pts[i];
  if (!rgb[0].empty()) {
    out.names = {"red", "green", "blue"};
    for (auto& c : rgb) out.values.push_back(std::move(c));
  }
  return out;
}

PaintedPoints read_csv_paint(const std::string& path, const Points* nodes) {
  CsvTable table = read_csv_table(path, "a CSV paint file");
  PaintedPoints out;
  out.path = path;
  out.names = std::move(table.names);
  out.values = std::move(table.columns);
  const bool by_node = !out.names.empty() && out.names[0] == "node";
  if (!by_node && (out.names.size() < 3 || out.names[0] != "x" || out.names[1] != "y" || out.names[2] != "z"))
    throw Error(path + ":1: expected a header row starting with x,y,z or with node");
  const std::size_t n = out.values[0].size();
  out.x.resize(3, static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    if (by_node) {
      const double v = out.values[0][i];
      if (!nodes || v != std::floor(v) || v < 0 || v >= nodes->cols())
        throw Error(path + ": row " + std::to_string(i + 2) + ": node " + std::to_string(v) +
                    " is not a node of the mesh (expected 0.." + std::to_string(nodes ? nodes->cols() - 1 : -1) + ")");
      out.x.col(i) = nodes->col(static_cast<Eigen::Index>(v));
    } else {
      out.x.col(i) = Eigen::Vector3d(out.values[0][i], out.values[1][i], out.values[2][i]);
    }
  }
  return out;
}

}  // namespace

const std::vector<double>* PaintedPoints::find(const std::string& name) const {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return &values[k];
  return nullptr;
}

PaintedPoints read_paint(const std::string& path, const Points* nodes) {
  check_input_file(path, "a paint file (.ply, .obj or .csv)", input_limits::kPaint);
  const auto dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  PaintedPoints p;
  if (ext == ".ply")
    p = read_ply(path);
  else if (ext == ".obj")
    p = read_obj_paint(path);
  else if (ext == ".csv")
    p = read_csv_paint(path, nodes);
  else
    throw Error(path + ": unknown paint file type (expected .ply, .obj or .csv)");
  if (p.x.cols() == 0) throw Error(path + ": no painted vertices");
  for (Eigen::Index i = 0; i < p.x.cols(); ++i)
    if (!p.x.col(i).allFinite())
      throw Error(path + ": vertex " + std::to_string(i) + " has a position that is not a finite number");
  // Weights and labels too: a NaN weight is in no zone and not out of one either.
  for (std::size_t k = 0; k < p.names.size(); ++k)
    for (std::size_t i = 0; i < p.values[k].size(); ++i)
      if (!std::isfinite(p.values[k][i]))
        throw Error(path + ": vertex " + std::to_string(i) + "'s " + p.names[k] + " is " +
                    (std::isnan(p.values[k][i]) ? "NaN" : "infinite") + " (expected a finite number)");
  return p;
}

}  // namespace isochor
