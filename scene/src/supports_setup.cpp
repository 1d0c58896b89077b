#include "isochor/scene/supports_setup.hpp"

#include <Eigen/SVD>
#include <cmath>

#include "isochor/base/error.hpp"

namespace isochor {

std::unique_ptr<ComponentSupports> make_supports(const Scene& scene, const DofMap& dofs) {
  std::vector<ComponentSupports::Row> rows;
  std::vector<std::vector<Vec3>> dirs(scene.mesh.num_nodes());
  std::vector<int> first_driver(scene.mesh.num_nodes(), -1);
  for (std::size_t k = 0; k < scene.boundary.size(); ++k) {
    const Driver& d = scene.boundary[k];
    for (int v : d.nodes)
      for (const Vec3& dir : d.held) {
        if (dofs.free_index[v] < 0)
          throw Error(scene.file.name() + ": boundary[" + std::to_string(k) + "]: node " + std::to_string(v) +
                      " is not an unknown of this model (the mass-spring model simulates only its surface; expected "
                      "surface nodes)");
        if (first_driver[v] < 0) first_driver[v] = static_cast<int>(k);
        dirs[v].push_back(dir);
        // A node's held directions must be independent, or its rows would be singular.
        Eigen::MatrixXd D(3, dirs[v].size());
        for (std::size_t i = 0; i < dirs[v].size(); ++i) D.col(static_cast<Index>(i)) = dirs[v][i];
        const Eigen::JacobiSVD<Eigen::MatrixXd> svd(D);
        if (dirs[v].size() > 3 || svd.singularValues().minCoeff() < 1e-6)
          throw Error(scene.file.name() + ": boundary[" + std::to_string(k) + "]: node " + std::to_string(v) +
                      " is held along a direction that boundary[" + std::to_string(first_driver[v]) +
                      "] already holds (expected independent components on each node)");
        rows.push_back({v, dir, &d});
      }
  }
  if (rows.empty()) return nullptr;
  return std::make_unique<ComponentSupports>(scene.mesh, std::move(rows), dofs, std::cbrt(scene.mesh.rest_volume()));
}

}  // namespace isochor
