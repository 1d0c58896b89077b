#include "isochor/core/csv.hpp"
#include "isochor/core/input_file.hpp"
#include "isochor/core/paint.hpp"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <numeric>
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

using KdTree = nanoflann::KDTreeEigenMatrixAdaptor<Points, 3, nanoflann::metric_L2_Simple, false>;

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

std::vector<std::vector<double>> paint_membership(const PaintedPoints& p, const PaintRule& rule) {
  const std::size_t n = static_cast<std::size_t>(p.x.cols());
  std::vector<std::vector<double>> in(rule.zones.size(), std::vector<double>(n, 0.0));
  auto need = [&](const std::string& name) {
    const auto* v = p.find(name);
    if (!v) {
      std::string have;
      for (const auto& h : p.names) have += (have.empty() ? "" : ", ") + h;
      throw Error(p.path + ": no vertex property \"" + name + "\" (it has: " + (have.empty() ? "none" : have) + ")");
    }
    return v;
  };
  switch (rule.by) {
    case PaintRule::By::labels: {
      const auto* L = need(rule.property);
      for (std::size_t z = 0; z < rule.zones.size(); ++z)
        for (std::size_t i = 0; i < n; ++i) in[z][i] = (*L)[i] == static_cast<double>(rule.labels[z]);
      break;
    }
    case PaintRule::By::colors: {
      const auto *r = need("red"), *g = need("green"), *b = need("blue");
      for (std::size_t i = 0; i < n; ++i) {
        // The nearest listed colour within the tolerance (one zone per vertex).
        const Eigen::Vector3d c((*r)[i], (*g)[i], (*b)[i]);
        int best = -1;
        double best_d = rule.color_tolerance;
        for (std::size_t z = 0; z < rule.zones.size(); ++z) {
          const double d = (c - rule.colors[z]).norm();
          if (d <= best_d) best = static_cast<int>(z), best_d = d;
        }
        if (best >= 0) in[best][i] = 1;
      }
      break;
    }
    case PaintRule::By::weights:
      for (std::size_t z = 0; z < rule.zones.size(); ++z) {
        const auto* w = need(rule.weights[z]);
        for (std::size_t i = 0; i < n; ++i) in[z][i] = (*w)[i];
      }
      break;
  }
  return in;
}

Eigen::Vector3d barycentric(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c) {
  const Eigen::Vector3d u = b - a, w = c - a, r = q - a;
  const double uu = u.dot(u), uw = u.dot(w), ww = w.dot(w), det = uu * ww - uw * uw;
  if (!(det > 0)) return Eigen::Vector3d(1, 0, 0);
  const double l1 = (ww * r.dot(u) - uw * r.dot(w)) / det, l2 = (uu * r.dot(w) - uw * r.dot(u)) / det;
  return Eigen::Vector3d(1 - l1 - l2, l1, l2);
}

Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  // Voronoi regions of the vertices, edges and face (Ericson, Real-Time Collision Detection, 5.1.5).
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

std::vector<std::vector<int>> painted_zones(const Mesh& mesh, const PaintedPoints& p,
                                            const std::vector<std::vector<double>>& membership, double tolerance) {
  const Points& X = mesh.rest_positions();
  const std::size_t Z = membership.size();
  // Surface nodes: the paint of the nearest painted point.
  KdTree painted(3, std::cref(p.x), 10);
  std::vector<std::vector<double>> node_in(Z, std::vector<double>(static_cast<std::size_t>(mesh.num_nodes()), 0.0));
  for (int v : mesh.surface_nodes()) {
    Eigen::Index nearest = 0;
    double d2 = 0;
    painted.index->knnSearch(X.col(v).data(), 1, &nearest, &d2);
    if (std::sqrt(d2) > tolerance) {
      char buf[300];
      std::snprintf(buf, sizeof buf,
                    ": surface node %d at [%g, %g, %g] is %.3g m from the nearest painted vertex (more than %g m: "
                    "expected the paint of this mesh's surface)",
                    v, X(0, v), X(1, v), X(2, v), std::sqrt(d2), tolerance);
      throw Error(p.path + buf);
    }
    for (std::size_t z = 0; z < Z; ++z) node_in[z][v] = membership[z][static_cast<std::size_t>(nearest)];
  }
  const auto& S = mesh.surface();
  Points centroid(3, static_cast<Eigen::Index>(S.size()));
  double reach = 0;  // the largest distance from a triangle's centroid to its corners
  for (std::size_t f = 0; f < S.size(); ++f) {
    centroid.col(f) = (X.col(S[f][0]) + X.col(S[f][1]) + X.col(S[f][2])) / 3.0;
    for (int v : S[f]) reach = std::max(reach, (X.col(v) - centroid.col(f)).norm());
  }
  // Tets: the paint at the surface point nearest to the centroid, interpolated linearly on its
  // triangle. The nearest triangle's centroid is within (the distance to the nearest centroid)
  // + reach: search that ball exactly.
  KdTree tris(3, std::cref(centroid), 10);
  std::vector<std::vector<int>> zones(Z);
  std::vector<std::pair<Eigen::Index, double>> found;
  for (int e = 0; e < mesh.num_tets(); ++e) {
    const Tet& t = mesh.tets()[e];
    const Eigen::Vector3d c = (X.col(t[0]) + X.col(t[1]) + X.col(t[2]) + X.col(t[3])) / 4.0;
    Eigen::Index nearest = 0;
    double d2 = 0;
    tris.index->knnSearch(c.data(), 1, &nearest, &d2);
    const double r = std::sqrt(d2) + reach;
    found.clear();
    tris.index->radiusSearch(c.data(), r * r * (1 + 1e-12), found, nanoflann::SearchParams());
    std::size_t best = static_cast<std::size_t>(nearest);
    double best_d = std::numeric_limits<double>::infinity();
    Eigen::Vector3d at = c;
    for (const auto& item : found) {
      const Tri& f = S[static_cast<std::size_t>(item.first)];
      const Eigen::Vector3d q = closest_on_triangle(c, X.col(f[0]), X.col(f[1]), X.col(f[2]));
      const double d = (q - c).squaredNorm();
      if (d < best_d) best_d = d, best = static_cast<std::size_t>(item.first), at = q;
    }
    const Tri& f = S[best];
    const Eigen::Vector3d l = barycentric(at, X.col(f[0]), X.col(f[1]), X.col(f[2]));
    for (std::size_t z = 0; z < Z; ++z) {
      const double paint = l[0] * node_in[z][f[0]] + l[1] * node_in[z][f[1]] + l[2] * node_in[z][f[2]];
      if (paint >= 0.5) zones[z].push_back(e);
    }
  }
  return zones;
}

std::vector<std::vector<int>> connected_pieces(const Mesh& mesh, const std::vector<int>& tets) {
  // Tets sharing a node are connected (not only through faces: a tet that touches a zone along an
  // edge, as the zone's border on a fine mesh leaves some, is not a piece of its own).
  std::vector<int> parent(tets.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<int> node_owner(static_cast<std::size_t>(mesh.num_nodes()), -1);
  for (std::size_t k = 0; k < tets.size(); ++k)
    for (int v : mesh.tets()[tets[k]]) {
      if (node_owner[v] < 0)
        node_owner[v] = static_cast<int>(k);
      else
        parent[root(static_cast<int>(k))] = root(node_owner[v]);
    }
  std::map<int, std::vector<int>> pieces;
  for (std::size_t k = 0; k < tets.size(); ++k) pieces[root(static_cast<int>(k))].push_back(tets[k]);
  std::vector<std::vector<int>> out;
  for (auto& [r, v] : pieces) out.push_back(std::move(v));
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return out;
}

}  // namespace isochor
