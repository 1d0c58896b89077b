// A symmetric positive definite test matrix of 3x3 node blocks, for the PCG tests: the 7-point
// Laplacian on a k^3 grid of nodes times a positive definite 3x3 block, plus the identity; and its
// pattern in the integrators' form.
#pragma once
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <vector>

#include "isochor/integrators/sparse_pattern.hpp"

namespace isochor::test {

inline Eigen::SparseMatrix<double> block_laplacian(int k) {
  const int nodes = k * k * k;
  auto id = [&](int i, int j, int l) { return (i * k + j) * k + l; };
  Eigen::Matrix3d B;
  B << 2.0, 0.3, 0.1, 0.3, 1.5, 0.2, 0.1, 0.2, 1.0;
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j)
      for (int l = 0; l < k; ++l) {
        const int a = id(i, j, l);
        auto couple = [&](int b, double w) {
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c)
              t.emplace_back(3 * a + r, 3 * b + c, w * B(r, c) + (a == b && r == c ? 1.0 : 0.0));
        };
        couple(a, 6.0);
        if (i > 0) couple(id(i - 1, j, l), -1.0);
        if (i + 1 < k) couple(id(i + 1, j, l), -1.0);
        if (j > 0) couple(id(i, j - 1, l), -1.0);
        if (j + 1 < k) couple(id(i, j + 1, l), -1.0);
        if (l > 0) couple(id(i, j, l - 1), -1.0);
        if (l + 1 < k) couple(id(i, j, l + 1), -1.0);
      }
  Eigen::SparseMatrix<double> S(3 * nodes, 3 * nodes);
  S.setFromTriplets(t.begin(), t.end());
  S.makeCompressed();
  return S;
}

inline SparsePattern pattern_of(const Eigen::SparseMatrix<double>& S) {
  SparsePattern p;
  p.n = S.cols();
  p.col_ptr.assign(S.outerIndexPtr(), S.outerIndexPtr() + S.cols() + 1);
  p.row_ind.assign(S.innerIndexPtr(), S.innerIndexPtr() + S.nonZeros());
  return p;
}

}  // namespace isochor::test
