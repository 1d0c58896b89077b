// The [mesh] block of a scene.
#include <algorithm>
#include <cctype>
#include <filesystem>

#include <cmath>
#include <cstdio>

#include "isochor/base/error.hpp"
#include "isochor/core/memory.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/core/scene_file.hpp"

namespace isochor {

// Before meshing: a mesh of about `tets` tets must fit this machine's memory while it runs.
void check_tets(const Section& s, const std::string& key, double tets) {
  const double ram = physical_memory_mb();
  const double need = kBaselineMb + tets * kMinBytesPerTet / (1024.0 * 1024.0);
  if (need <= ram) return;
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "makes about %.3g tets, which need at least %.3g GB of memory while running (%.0f KB per tet); this "
                "machine has %.3g GB (expected at most about %.2g tets)",
                tets, need / 1024, kMinBytesPerTet / 1024, ram / 1024,
                (ram - kBaselineMb) * 1024 * 1024 / kMinBytesPerTet);
  s.fail(key, buf);
}

// Gmsh meshes with an absolute geometric tolerance of 1e-8 m: shapes near it abort inside Gmsh.
void check_size(const Section& s, const std::string& key, double size) {
  if (size >= 1e-6) return;
  char buf[200];
  std::snprintf(
      buf, sizeof buf,
      "%g m is too small to mesh (Gmsh's geometric tolerance is 1e-8 m; expected at least 1e-6 m: sizes are in "
      "metres)",
      size);
  s.fail(key, buf);
}

// Tets of a Gmsh mesh of volume V at edge length h, at least.
double gmsh_tets(double volume, double h) { return kGmshTetsPerEdgeCube * volume / (h * h * h); }

namespace {

// A closed surface file filled with tets: with an edge_length, the tets it makes are estimated
// from the enclosed volume before Gmsh runs, as for the shapes.
Mesh mesh_surface_file(const Section& s, const std::string& path) {
  const double h = s.number("edge_length", 0.0);
  if (h > 0) {
    check_size(s, "edge_length", h);
    Points x;
    std::vector<Tri> tris;
    read_surface(path, x, tris);
    check_tets(s, "edge_length", gmsh_tets(std::abs(surface_volume(x, tris)), h));
  }
  return mesh_closed_surface(path, h);
}

// [mesh] parameters = { N = 64 }: numbers a .geo script reads, each name a Gmsh identifier.
std::vector<std::pair<std::string, double>> geo_parameters(const Section& s) {
  std::vector<std::pair<std::string, double>> out;
  const Section p = s.table("parameters");
  if (!p.exists()) return out;
  for (const std::string& name : p.keys()) {
    const bool identifier = !name.empty() && !std::isdigit(static_cast<unsigned char>(name[0])) &&
                            std::all_of(name.begin(), name.end(),
                                        [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
    if (!identifier) p.fail(name, "is not a .geo variable name (expected letters, digits and _, not first a digit)");
    out.emplace_back(name, p.number(name, 0.0));
  }
  return out;
}

// A .geo script with its parameters and edge length; the tets it will make are bounded from below
// before Gmsh meshes the volume, and a script too fine for the machine stops there, naming the key
// that sets the size (the first parameter where there are any, as cook.geo's N; else edge_length).
Mesh mesh_geo_file(const Section& s, const std::string& path) {
  const double h = s.number("edge_length", 0.0);
  if (h > 0) check_size(s, "edge_length", h);
  const auto parameters = geo_parameters(s);
  const Section named = parameters.empty() ? s : s.table("parameters");
  const std::string key = !parameters.empty() ? parameters.front().first : h > 0 ? "edge_length" : "file";
  return read_geo(path, h, parameters, [&](double tets) { check_tets(named, key, tets); });
}

// [mesh] file = "...": by its extension.
Mesh mesh_from_file(const Section& s, const SceneFile& file, const Eigen::Vector3d& center) {
  const std::string name = s.string("file", "");
  const std::string path = file.resolve_path(name);
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(c));
  if (ext != ".geo" && s.has("parameters")) s.fail("parameters", "applies to a .geo script only");
  Mesh m;
  if (ext == ".msh")
    m = read_msh(path);
  else if (ext == ".node" || ext == ".ele")
    m = read_tetgen(path);
  else if (ext == ".obj" || ext == ".stl")
    m = mesh_surface_file(s, path);
  else if (ext == ".geo")
    m = mesh_geo_file(s, path);
  else
    s.fail("file", "\"" + name + "\" has an unknown extension, expected .msh, .geo, .node, .ele, .obj or .stl");
  if (center != Eigen::Vector3d::Zero()) s.fail("center", "applies to shapes only, not to a mesh file");
  return m;
}

}  // namespace

Mesh mesh_from_scene(const Section& s, const SceneFile& file) {
  const bool has_file = s.has("file"), has_shape = s.has("shape");
  if (has_file && has_shape) s.fail("file", "give either shape or file, not both");
  if (!has_file && !has_shape)
    s.fail(
        "shape",
        "missing, expected shape = \"box\" | \"capsule\" | \"cylinder\" | \"sphere\" | \"two_tets\" or file = \"...\"");
  const Eigen::Vector3d center = s.vec3("center");
  if (has_file) return mesh_from_file(s, file, center);
  const std::string shape = s.string("shape", "");
  if (shape == "box") {
    const auto cells = s.int3("cells", {4, 4, 4});
    const int split = static_cast<int>(s.integer("split", 6));
    check_tets(s, "cells",
               static_cast<double>(cells[0]) * static_cast<double>(cells[1]) * static_cast<double>(cells[2]) * split);
    const double sliver = s.number("sliver_ratio");
    const Eigen::Vector3d size = s.vec3("size", Eigen::Vector3d::Ones());
    check_size(s, "size", size.minCoeff());  // masses of a box far below a micrometre underflow
    return make_box(size, cells, center, split, sliver);
  }
  if (shape == "cylinder") {
    const double r = s.number("radius", 0.5), height = s.number("height");
    const int resolution = static_cast<int>(s.integer("resolution"));
    check_size(s, "radius", r);
    check_size(s, "height", height);
    check_tets(s, "resolution", gmsh_tets(M_PI * r * r * height, 2 * M_PI * r / resolution));
    return make_cylinder(r, height, resolution, center);
  }
  if (shape == "capsule") {
    if (!s.has("from") || !s.has("to"))
      s.fail(s.has("from") ? "to" : "from",
             "missing, a capsule needs the ends of its axis, from = [x, y, z] and to = [x, y, z] (m)");
    const Eigen::Vector3d a = s.vec3("from", {}), b = s.vec3("to", {});
    if ((b - a).norm() == 0) s.fail("to", "expected a point other than `from`");
    const double r = s.number("radius", 0.5);
    const double h = s.number("edge_length", r / 3);
    if (h <= 0) s.fail("edge_length", "expected a number > 0 for a capsule, got " + std::to_string(h));
    if (center != Eigen::Vector3d::Zero())
      s.fail("center", "does not apply to a capsule (it lies between from and to)");
    check_size(s, "radius", r);
    check_size(s, "edge_length", h);
    check_tets(s, "edge_length", gmsh_tets(M_PI * r * r * (b - a).norm() + 4.0 / 3.0 * M_PI * r * r * r, h));
    return make_capsule(a, b, r, h);
  }
  if (shape == "sphere") {
    const double r = s.number("radius", 1.0);
    const double h = s.number("edge_length", 0.0);
    const long target = s.integer("target_tets");
    if (h > 0 && s.has("target_tets")) s.fail("edge_length", "give either edge_length or target_tets, not both");
    const double inner = s.number("inner_radius");
    if (inner >= r) s.fail("inner_radius", "expected less than radius (" + std::to_string(r) + " m)");
    check_size(s, "radius", r);
    if (inner > 0) check_size(s, "inner_radius", inner);
    if (h > 0) check_size(s, "edge_length", h);
    const double volume = 4.0 / 3.0 * M_PI * (r * r * r - inner * inner * inner);
    if (h > 0)
      check_tets(s, "edge_length", gmsh_tets(volume, h));
    else
      check_tets(s, "target_tets", static_cast<double>(target));
    return make_sphere(r, h, target, center, inner);
  }
  Mesh m = make_two_tets(s.number("edge"));
  if (center != Eigen::Vector3d::Zero()) s.fail("center", "does not apply to two_tets");
  return m;
}

}  // namespace isochor
