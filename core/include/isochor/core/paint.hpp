// Painted zones (the CNH paper's section 6): zones painted on the surface as per-vertex labels,
// colours or weights, carried into the volume. Each surface node of the mesh takes the paint of
// the nearest painted vertex (per zone: 1 or 0 for a label or colour, the weight itself); each
// tet takes the paint of the surface point nearest to its centroid (where the path along the
// gradient of the distance to the surface ends: the paper allows any distance field),
// interpolated linearly on that point's triangle, and is in every zone whose paint there is at
// least 1/2. (The paper gives each triangle a zone; interpolating puts a zone's border where the
// paint changes instead of on triangle edges, and a linear paint is carried exactly.)
#pragma once
#include <string>
#include <vector>

#include "isochor/core/mesh.hpp"

namespace isochor {

// Points with named per-vertex properties, read from a paint file:
//   .ply  the vertex element's position (x, y, z) and every scalar property (ASCII or binary);
//         red/green/blue/alpha of type uchar are scaled to 0..1
//   .obj  `v x y z [r g b]` lines: red, green, blue (0..1) when given
//   .csv  a header row naming the columns, then one row per vertex: `x,y,z,...` (positions) or
//         `node,...` (mesh node indices, as in /mesh/rest_positions: positions from `nodes`)
struct PaintedPoints {
  std::string path;
  Points x;
  std::vector<std::string> names;           // property names, in file order
  std::vector<std::vector<double>> values;  // per property, one value per point
  const std::vector<double>* find(const std::string& name) const;
};
PaintedPoints read_paint(const std::string& path, const Points* nodes = nullptr);

// How much each painted point belongs to each zone: for each zone, a value per point (1 or 0 for
// labels and colours, the weight for weights).
struct PaintRule {
  enum class By { labels, colors, weights };
  By by = By::labels;
  std::vector<std::string> zones;       // zone names
  std::string property = "label";       // labels: the property holding them
  std::vector<long> labels;             // labels: per zone
  std::vector<Eigen::Vector3d> colors;  // colors: per zone, 0..1
  double color_tolerance = 0.1;         // colors: largest distance in RGB (0..1) to count as that colour
  std::vector<std::string> weights;     // weights: per zone, the property
};
// Throws an Error naming the file and the missing property.
std::vector<std::vector<double>> paint_membership(const PaintedPoints& p, const PaintRule& rule);

// The tets of each zone. `tolerance` (m): a surface node farther than this from every painted
// point means the paint is of another surface (an Error naming the node and the distance).
std::vector<std::vector<int>> painted_zones(const Mesh& mesh, const PaintedPoints& p,
                                            const std::vector<std::vector<double>>& membership, double tolerance);

// The pieces of a set of tets (tets sharing a node are connected), largest first.
std::vector<std::vector<int>> connected_pieces(const Mesh& mesh, const std::vector<int>& tets);

// The barycentric weights of q (a point of the triangle's plane) on the triangle (a, b, c);
// (1, 0, 0) for a degenerate triangle.
Eigen::Vector3d barycentric(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c);

// The closest point to p on the triangle (a, b, c).
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c);

}  // namespace isochor
