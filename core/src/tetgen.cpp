// TetGen .node/.ele files: whitespace separated, '#' comments, 0- or 1-based numbering.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "isochor/core/input_file.hpp"
#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"

namespace isochor {

namespace {

class LineReader {
 public:
  explicit LineReader(const std::string& path) : path_(path) {
    check_input_file(path, "a TetGen file", input_limits::kMesh);
    in_.open(path);
    if (!in_) throw Error(path + ": cannot be read (expected a TetGen file)");
  }
  // The next non-empty line without comments, split into tokens; false at the end.
  bool next(std::vector<std::string>& tokens) {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_no_;
      auto hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      std::istringstream s(line);
      tokens.clear();
      for (std::string t; s >> t;) tokens.push_back(t);
      if (!tokens.empty()) return true;
    }
    return false;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(path_ + ":" + std::to_string(line_no_) + ": " + what);
  }
  double real(const std::string& t) const {
    try {
      std::size_t used;
      double v = std::stod(t, &used);
      if (used == t.size() && std::isfinite(v)) return v;
    } catch (...) {
    }
    fail("\"" + t + "\" is not a number");
  }
  long integer(const std::string& t) const {
    try {
      std::size_t used;
      long v = std::stol(t, &used);
      if (used == t.size()) return v;
    } catch (...) {
    }
    fail("\"" + t + "\" is not an integer");
  }

 private:
  std::string path_;
  std::ifstream in_;
  long line_no_ = 0;
};

std::string attribute_name(double a) {
  std::ostringstream s;
  s << a;
  return s.str();
}

// The bytes of a file (0 when unknown): a large count the file cannot hold is refused before
// anything is allocated for it (a point line has at least 8 bytes, a tet line 10: the fuzzer's
// 4294967296-point header ran out of memory). A small file that ends early says where.
double file_bytes(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0.0 : static_cast<double>(size);
}

// The .node file: positions, boundary markers (0: none), and the first index (0 or 1).
struct TetgenNodes {
  Points x;
  std::vector<long> markers;
  long first = -1;
};

TetgenNodes read_nodes(const std::string& node_path) {
  LineReader nodes(node_path);
  std::vector<std::string> tok;
  if (!nodes.next(tok) || tok.size() < 2) nodes.fail("expected a header: <#points> 3 <#attributes> <#markers>");
  const long n = nodes.integer(tok[0]);
  if (n <= 0) nodes.fail("expected a positive number of points, got " + tok[0]);
  if (nodes.integer(tok[1]) != 3) nodes.fail("expected dimension 3, got " + tok[1]);
  if (n > 1000000 && static_cast<double>(n) > file_bytes(node_path) / 8)
    nodes.fail("the header announces " + tok[0] + " points, more than the file can hold");
  const long nattr = tok.size() > 2 ? nodes.integer(tok[2]) : 0;
  const long nmark = tok.size() > 3 ? nodes.integer(tok[3]) : 0;
  if (nattr < 0 || nattr > 1000) nodes.fail("expected a number of attributes from 0 to 1000, got " + tok[2]);
  if (nmark < 0 || nmark > 1) nodes.fail("expected 0 or 1 boundary markers, got " + tok[3]);
  TetgenNodes r{Points(3, n), std::vector<long>(n, 0), -1};
  std::vector<char> seen(n, 0);
  for (long i = 0; i < n; ++i) {
    if (!nodes.next(tok))
      nodes.fail("expected " + std::to_string(n) + " points, the file ends after " + std::to_string(i));
    if (static_cast<long>(tok.size()) < 4 + nattr + nmark)
      nodes.fail("expected <index> x y z" + std::string(nattr ? " <attributes>" : "") + (nmark ? " <marker>" : "") +
                 ", got " + std::to_string(tok.size()) + " fields");
    long idx = nodes.integer(tok[0]);
    if (r.first < 0) {
      r.first = idx;
      if (r.first != 0 && r.first != 1) nodes.fail("the first point index is " + tok[0] + ", expected 0 or 1");
    }
    long k = idx - r.first;
    if (k < 0 || k >= n || seen[k]) nodes.fail("point index " + tok[0] + " is out of range or repeated");
    seen[k] = 1;
    for (int d = 0; d < 3; ++d) r.x(d, k) = nodes.real(tok[1 + d]);
    if (nmark) r.markers[k] = nodes.integer(tok[4 + nattr]);
  }
  return r;
}

// The .ele file: tets (node indices from `first`), and a zone per region attribute.
std::vector<Tet> read_elements(const std::string& ele_path, const std::string& node_path, long n, long first,
                               std::map<std::string, std::vector<int>>& zones) {
  LineReader ele(ele_path);
  std::vector<std::string> tok;
  if (!ele.next(tok) || tok.size() < 2) ele.fail("expected a header: <#tets> <nodes per tet> <#attributes>");
  const long T = ele.integer(tok[0]);
  if (T <= 0) ele.fail("expected a positive number of tets, got " + tok[0]);
  const long per = ele.integer(tok[1]);
  if (per != 4) ele.fail("expected 4 nodes per tet (linear tets), got " + tok[1]);
  if (T > 1000000 && static_cast<double>(T) > file_bytes(ele_path) / 10)
    ele.fail("the header announces " + tok[0] + " tets, more than the file can hold");
  const long tattr = tok.size() > 2 ? ele.integer(tok[2]) : 0;
  if (tattr < 0 || tattr > 1000) ele.fail("expected a number of attributes from 0 to 1000, got " + tok[2]);
  std::vector<Tet> tets(T);
  for (long e = 0; e < T; ++e) {
    if (!ele.next(tok)) ele.fail("expected " + std::to_string(T) + " tets, the file ends after " + std::to_string(e));
    if (static_cast<long>(tok.size()) < 5 + tattr)
      ele.fail("expected <index> n1 n2 n3 n4" + std::string(tattr ? " <region attribute>" : "") + ", got " +
               std::to_string(tok.size()) + " fields");
    for (int k = 0; k < 4; ++k) {
      long v = ele.integer(tok[1 + k]) - first;
      if (v < 0 || v >= n) ele.fail("node " + tok[1 + k] + " is not in " + node_path);
      tets[e][k] = static_cast<int>(v);
    }
    if (tattr) zones["region_" + attribute_name(ele.real(tok[5]))].push_back(static_cast<int>(e));
  }
  return tets;
}

}  // namespace

Mesh read_tetgen(const std::string& path) {
  std::filesystem::path p(path);
  std::string base =
      (p.extension() == ".node" || p.extension() == ".ele") ? (p.parent_path() / p.stem()).string() : path;
  const std::string node_path = base + ".node", ele_path = base + ".ele";
  TetgenNodes nodes = read_nodes(node_path);
  const long n = nodes.x.cols();
  std::map<std::string, std::vector<int>> zones;
  std::vector<Tet> tets = read_elements(ele_path, node_path, n, nodes.first, zones);
  std::map<std::string, std::vector<int>> sets;
  for (long i = 0; i < n; ++i)
    if (nodes.markers[i] != 0) sets["marker_" + std::to_string(nodes.markers[i])].push_back(static_cast<int>(i));
  compact_unused_nodes(nodes.x, tets, &sets);
  Mesh m(std::move(nodes.x), std::move(tets), ele_path);
  m.zones = std::move(zones);
  m.node_sets = std::move(sets);
  return m;
}

}  // namespace isochor
