#include <algorithm>
#include <cmath>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"

namespace isochor {

Mesh make_box(const Eigen::Vector3d& size, const std::array<long, 3>& cells, const Eigen::Vector3d& center, int split,
              double sliver_ratio) {
  if (split != 5 && split != 6) throw Error("box: split = " + std::to_string(split) + ", expected 5 or 6");
  if (!(sliver_ratio >= 1.0)) throw Error("box: sliver_ratio = " + std::to_string(sliver_ratio) + ", expected >= 1");
  const long nx = cells[0], ny = cells[1], nz = cells[2];
  const long px = nx + 1, py = ny + 1, pz = nz + 1;
  Points x(3, px * py * pz);
  auto id = [&](long i, long j, long k) { return static_cast<int>(i + px * (j + py * k)); };
  const Eigen::Vector3d lo = center - size / 2;
  // Node coordinates along each axis: even cell layers of width w, odd ones w / sliver_ratio.
  std::array<std::vector<double>, 3> coord;
  for (int a = 0; a < 3; ++a) {
    const long nc = cells[static_cast<std::size_t>(a)], thin = nc / 2, thick = nc - thin;
    const double w = size[a] / (static_cast<double>(thick) + static_cast<double>(thin) / sliver_ratio);
    coord[a].assign(1, lo[a]);
    for (long c = 0; c < nc; ++c) coord[a].push_back(coord[a].back() + (c % 2 == 0 ? w : w / sliver_ratio));
    coord[a].back() = lo[a] + size[a];
    if (sliver_ratio == 1.0)  // the regular grid, exactly as before
      for (long c = 0; c <= nc; ++c) coord[a][c] = lo[a] + size[a] * c / nc;
  }
  for (long k = 0; k < pz; ++k)
    for (long j = 0; j < py; ++j)
      for (long i = 0; i < px; ++i) x.col(id(i, j, k)) = Eigen::Vector3d(coord[0][i], coord[1][j], coord[2][k]);

  std::vector<Tet> tets;
  tets.reserve(nx * ny * nz * split);
  for (long k = 0; k < nz; ++k)
    for (long j = 0; j < ny; ++j)
      for (long i = 0; i < nx; ++i) {
        // Corner c = bx + 2 by + 4 bz.
        int c[8];
        for (int b = 0; b < 8; ++b) c[b] = id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        if (split == 6) {
          // Kuhn: one tet per path 0 -> 7 along the cube edges; conforming for any neighbour.
          static constexpr int kPath[6][2] = {{1, 3}, {5, 1}, {3, 2}, {2, 6}, {4, 5}, {6, 4}};  // positive
          for (const auto& p : kPath) tets.push_back({c[0], c[p[0]], c[p[1]], c[7]});
        } else {
          // Central tet on the corners of one parity, four corner tets; parity alternates.
          static constexpr int kEven[5][4] = {{1, 2, 4, 7}, {0, 1, 2, 4}, {3, 2, 1, 7}, {5, 1, 4, 7}, {6, 4, 2, 7}};
          static constexpr int kOdd[5][4] = {
              {0, 5, 3, 6}, {1, 3, 0, 5}, {2, 0, 3, 6}, {4, 5, 0, 6}, {7, 3, 5, 6}};  // all positive
          const auto& t = ((i + j + k) % 2 == 0) ? kEven : kOdd;
          for (const auto& q : t) tets.push_back({c[q[0]], c[q[1]], c[q[2]], c[q[3]]});
        }
      }
  Mesh m(std::move(x), std::move(tets), "box");
  const char* names[3][2] = {{"xmin", "xmax"}, {"ymin", "ymax"}, {"zmin", "zmax"}};
  for (long k = 0; k < pz; ++k)
    for (long j = 0; j < py; ++j)
      for (long i = 0; i < px; ++i) {
        const long ijk[3] = {i, j, k}, n[3] = {nx, ny, nz};
        for (int a = 0; a < 3; ++a) {
          if (ijk[a] == 0) m.node_sets[names[a][0]].push_back(id(i, j, k));
          if (ijk[a] == n[a]) m.node_sets[names[a][1]].push_back(id(i, j, k));
        }
      }
  for (auto& [name, set] : m.node_sets) std::sort(set.begin(), set.end());
  return m;
}

Mesh make_two_tets(double edge) {
  const double r = edge / std::sqrt(3.0);        // circumradius of the shared face
  const double h = edge * std::sqrt(2.0 / 3.0);  // apex height of a regular tet
  Points x(3, 5);
  for (int i = 0; i < 3; ++i) {
    const double a = 2.0 * M_PI * i / 3.0;
    x.col(i) = Eigen::Vector3d(0.0, r * std::cos(a), r * std::sin(a));
  }
  x.col(3) = Eigen::Vector3d(-h, 0, 0);
  x.col(4) = Eigen::Vector3d(h, 0, 0);
  Mesh m(std::move(x), {{3, 0, 1, 2}, {4, 0, 2, 1}}, "two_tets");
  m.node_sets["left"] = {3};
  m.node_sets["right"] = {4};
  m.node_sets["face"] = {0, 1, 2};
  m.zones["left"] = {0};
  m.zones["right"] = {1};
  return m;
}

}  // namespace isochor
