// The [mesh] block of a scene.
#include <filesystem>

#include "isochor/error.hpp"
#include "isochor/meshing.hpp"
#include "isochor/scene_file.hpp"

namespace isochor {

Mesh mesh_from_scene(const Section& s, const SceneFile& file) {
  const bool has_file = s.has("file"), has_shape = s.has("shape");
  if (has_file && has_shape) s.fail("file", "give either shape or file, not both");
  if (!has_file && !has_shape) s.fail("shape", "missing, expected shape = \"box\" | \"capsule\" | \"cylinder\" | \"sphere\" | \"two_tets\" or file = \"...\"");
  const Eigen::Vector3d center = s.vec3("center", Eigen::Vector3d::Zero());
  if (has_file) {
    const std::string name = s.string("file", "");
    const std::string path = file.resolve_path(name);
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(c));
    Mesh m;
    if (ext == ".msh") m = read_msh(path);
    else if (ext == ".node" || ext == ".ele") m = read_tetgen(path);
    else if (ext == ".obj" || ext == ".stl") m = mesh_closed_surface(path, s.number("edge_length", 0.0, Range::non_negative()));
    else s.fail("file", "\"" + name + "\" has an unknown extension, expected .msh, .node, .ele, .obj or .stl");
    if (center != Eigen::Vector3d::Zero()) s.fail("center", "applies to shapes only, not to a mesh file");
    return m;
  }
  const std::string shape = s.string("shape", "", {"box", "capsule", "cylinder", "sphere", "two_tets"});
  if (shape == "box") {
    return make_box(s.vec3("size", Eigen::Vector3d::Ones(), Range::positive()), s.int3("cells", {4, 4, 4}, 1, 1000),
                    center, static_cast<int>(s.integer("split", 6, 5, 6)));
  }
  if (shape == "cylinder") {
    return make_cylinder(s.number("radius", 0.5, Range::positive()), s.number("height", 1.0, Range::positive()),
                         static_cast<int>(s.integer("resolution", 24, 6, 10000)), center);
  }
  if (shape == "capsule") {
    if (!s.has("from") || !s.has("to")) s.fail(s.has("from") ? "to" : "from", "missing, a capsule needs the ends of its axis, from = [x, y, z] and to = [x, y, z] (m)");
    const Eigen::Vector3d a = s.vec3("from", {}), b = s.vec3("to", {});
    if ((b - a).norm() == 0) s.fail("to", "expected a point other than `from`");
    const double r = s.number("radius", 0.5, Range::positive());
    const double h = s.number("edge_length", r / 3, Range::positive());
    if (center != Eigen::Vector3d::Zero()) s.fail("center", "does not apply to a capsule (it lies between from and to)");
    return make_capsule(a, b, r, h);
  }
  if (shape == "sphere") {
    const double r = s.number("radius", 1.0, Range::positive());
    const double h = s.number("edge_length", 0.0, Range::non_negative());
    const long target = s.integer("target_tets", 5000, 10, 100000000);
    if (h > 0 && s.has("target_tets")) s.fail("edge_length", "give either edge_length or target_tets, not both");
    const double inner = s.number("inner_radius", 0.0, Range::non_negative());
    if (inner >= r) s.fail("inner_radius", "expected less than radius (" + std::to_string(r) + " m)");
    return make_sphere(r, h, target, center, inner);
  }
  Mesh m = make_two_tets(s.number("edge", 1.0, Range::positive()));
  if (center != Eigen::Vector3d::Zero()) s.fail("center", "does not apply to two_tets");
  return m;
}

}  // namespace isochor
