// Triangle surfaces: Wavefront OBJ (polygons fan-triangulated) and STL (ASCII or binary).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "isochor/core/input_file.hpp"
#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"

namespace isochor {

void read_obj_surface(const std::string& path, Points& x, std::vector<Tri>& tris) {
  check_input_file(path, "an OBJ surface", input_limits::kSurface);
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot be read (expected an OBJ surface)");
  std::vector<Eigen::Vector3d> v;
  tris.clear();
  std::string line;
  long line_no = 0;
  auto fail = [&](const std::string& what) { throw Error(path + ":" + std::to_string(line_no) + ": " + what); };
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream s(line);
    std::string tag;
    if (!(s >> tag)) continue;
    if (tag == "v") {
      Eigen::Vector3d p;
      if (!(s >> p.x() >> p.y() >> p.z()) || !p.allFinite()) fail("expected a vertex: v x y z");
      v.push_back(p);
    } else if (tag == "f") {
      std::vector<int> poly;
      for (std::string t; s >> t;) {
        long idx;
        try {
          idx = std::stol(t.substr(0, t.find('/')));
        } catch (...) {
          fail("\"" + t + "\" is not a vertex index");
        }
        if (idx < 0) idx += static_cast<long>(v.size()) + 1;  // relative index
        if (idx < 1 || idx > static_cast<long>(v.size()))
          fail("vertex " + t + " is not defined (expected 1.." + std::to_string(v.size()) + ")");
        poly.push_back(static_cast<int>(idx - 1));
      }
      if (poly.size() < 3) fail("a face needs at least 3 vertices");
      for (std::size_t k = 1; k + 1 < poly.size(); ++k) tris.push_back({poly[0], poly[k], poly[k + 1]});
    }
  }
  x.resize(3, static_cast<Eigen::Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) x.col(i) = v[i];
}

void read_stl_surface(const std::string& path, Points& x, std::vector<Tri>& tris) {
  const std::string data = read_input_file(path, "an STL surface", input_limits::kSurface);
  std::vector<Eigen::Vector3d> corners;
  bool binary = false;
  if (data.size() >= 84) {
    std::uint32_t count;
    std::memcpy(&count, data.data() + 80, 4);
    binary = data.size() == 84 + 50 * static_cast<std::size_t>(count);
  }
  if (binary) {
    std::uint32_t count;
    std::memcpy(&count, data.data() + 80, 4);
    for (std::uint32_t f = 0; f < count; ++f)
      for (int k = 0; k < 3; ++k) {
        float p[3];
        std::memcpy(p, data.data() + 84 + 50 * f + 12 * (k + 1), 12);
        corners.emplace_back(p[0], p[1], p[2]);
      }
  } else {
    if (data.rfind("solid", 0) != 0) throw Error(path + ": not an STL file (expected ASCII 'solid ...' or binary STL)");
    std::istringstream s(data);
    for (std::string t; s >> t;)
      if (t == "vertex") {
        Eigen::Vector3d p;
        if (!(s >> p.x() >> p.y() >> p.z())) throw Error(path + ": a vertex line is not 'vertex x y z'");
        corners.push_back(p);
      }
    if (corners.size() % 3) throw Error(path + ": the number of vertices is not a multiple of 3");
  }
  // STL repeats vertices per triangle: merge equal positions.
  std::map<std::array<double, 3>, int> index;
  std::vector<Eigen::Vector3d> v;
  tris.clear();
  for (std::size_t f = 0; f < corners.size() / 3; ++f) {
    Tri t;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = corners[3 * f + k];
      if (!p.allFinite()) throw Error(path + ": triangle " + std::to_string(f) + " has a non-finite vertex");
      auto [it, added] = index.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, static_cast<int>(v.size()));
      if (added) v.push_back(p);
      t[k] = it->second;
    }
    tris.push_back(t);
  }
  x.resize(3, static_cast<Eigen::Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) x.col(i) = v[i];
}

void read_surface(const std::string& path, Points& x, std::vector<Tri>& tris) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext == ".obj")
    read_obj_surface(path, x, tris);
  else if (ext == ".stl")
    read_stl_surface(path, x, tris);
  else
    throw Error("\"" + path + "\" has an unknown extension, expected .obj or .stl");
}

}  // namespace isochor
