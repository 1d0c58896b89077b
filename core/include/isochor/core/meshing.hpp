// Meshes from procedural shapes and from files.
#pragma once
#include <functional>
#include <string>

#include "isochor/core/mesh.hpp"

namespace isochor {

class Section;
class SceneFile;

// Box of size (sx, sy, sz) centred at `center`, cells per axis, each hex cell split into 5 tets
// (alternating so that faces conform) or 6 tets (Kuhn split around the main diagonal).
// Node sets: xmin, xmax, ymin, ymax, zmin, zmax (the nodes on each face).
// sliver_ratio > 1 makes a deliberately bad mesh for robustness tests: along each axis the cell
// layers alternate thick and thin, the thin ones this many times thinner (the box's size kept),
// so thin layers hold slivers: smallest face angle atan(1 / (sqrt(2) sliver_ratio)), largest edge
// ratio sqrt(2 sliver_ratio^2 + 1).
Mesh make_box(const Eigen::Vector3d& size, const std::array<long, 3>& cells, const Eigen::Vector3d& center, int split,
              double sliver_ratio = 1.0);
// Two tets of equal volume sharing a face (the CNH paper's Figure 2). The shared face is an
// equilateral triangle of edge `edge` in the plane x = 0; apexes at x = -h and x = +h.
// Node sets: left (left apex), right (right apex), face (the shared face).
Mesh make_two_tets(double edge);
// Cylinder along z, meshed by Gmsh with an edge length of 2 pi r / resolution.
// Node sets: bottom, top (the nodes on the end discs).
Mesh make_cylinder(double radius, double height, int resolution, const Eigen::Vector3d& center);
// Sphere meshed by Gmsh, by edge length or (edge_length <= 0) by a target tet count; with
// inner_radius > 0 a hollow sphere (a thick-walled shell), its wall's nodes in the node sets
// "inner" and "outer".
Mesh make_sphere(double radius, double edge_length, long target_tets, const Eigen::Vector3d& center,
                 double inner_radius = 0.0);

// Capsule (a cylinder with hemispherical ends) around the segment a-b, meshed by Gmsh with the
// given edge length: a limb around its bones.
Mesh make_capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, double edge_length);

// Gmsh .msh (v2 or v4): tets; 3-D physical groups become zones, physical groups of any
// dimension become node sets.
Mesh read_msh(const std::string& path);
// A Gmsh .geo script (points, curves, surfaces, volumes, extrusions, the OpenCASCADE kernel's
// solids): its volumes meshed by Gmsh (edge_length > 0: that size everywhere; 0: the script's own
// sizes), physical groups as for read_msh. `parameters` (name, value) are defined before the
// script runs, so that they override its DefineConstant[...] values (cook.geo's N). check_tets,
// where given, sees a lower bound on the tets before the volume is meshed (from the curves' mesh:
// a script too fine for the machine stops there) and throws to stop.
Mesh read_geo(const std::string& path, double edge_length,
              const std::vector<std::pair<std::string, double>>& parameters = {},
              const std::function<void(double)>& check_tets = {});
// TetGen .node/.ele (`path` is either file or the common base name): 0- or 1-based; region
// attributes become zones region_<value>; non-zero boundary markers become node sets marker_<m>.
Mesh read_tetgen(const std::string& path);
// A closed, consistently oriented triangle surface (.obj or .stl) tetrahedralised by Gmsh without
// changing its triangles. `edge_length` > 0 sets the interior size, otherwise it follows the surface.
Mesh mesh_closed_surface(const std::string& path, double edge_length);
// The same for a surface in memory; `what` names it in errors.
Mesh mesh_closed_surface(const Points& x, std::vector<Tri> tris, double edge_length, const std::string& what);

// CGAL's 3D alpha wrap of any triangle soup (open, non-manifold, self-intersecting): a closed,
// outward oriented 2-manifold surface without self-intersections, `offset` outside the input,
// closing over gaps narrower than about `alpha` (both lengths). `what` names the input in errors.
void alpha_wrap(const Points& x, const std::vector<Tri>& tris, double alpha, double offset, Points& out_x,
                std::vector<Tri>& out_tris, const std::string& what);

// Surface readers (no tetrahedralisation): positions and triangles, duplicate STL vertices merged.
void read_obj_surface(const std::string& path, Points& x, std::vector<Tri>& tris);
void read_stl_surface(const std::string& path, Points& x, std::vector<Tri>& tris);
// Either, by the file's extension (.obj or .stl, any case); another extension is an Error.
void read_surface(const std::string& path, Points& x, std::vector<Tri>& tris);

// Checks before meshing, failing on the key `key` of section `s`: a mesh of about `tets` tets
// fits this machine's memory while it runs; a size is at least 1e-6 m (Gmsh's tolerance).
void check_tets(const Section& s, const std::string& key, double tets);
void check_size(const Section& s, const std::string& key, double size);
// Tets of a Gmsh mesh of volume V at edge length h, at least.
double gmsh_tets(double volume, double h);

// The [mesh] block of a scene: a shape or a file.
Mesh mesh_from_scene(const Section& mesh, const SceneFile& file);

}  // namespace isochor
