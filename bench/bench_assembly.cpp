// Assembly throughput on a sphere: tets per second for energy + gradient and for energy +
// gradient + Hessian fill into the fixed pattern, on 1 and 2 threads (argument 2).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <memory>

#include <map>

#include "isochor/assembly.hpp"
#include "isochor/meshing.hpp"

namespace {
using namespace isochor;

struct Ball {
  Mesh mesh;
  DofMap dofs;
  std::unique_ptr<ElasticAssembly> assembly;
  Points x;
  explicit Ball(long tets) : mesh(make_sphere(0.1, 0.0, tets, Eigen::Vector3d::Zero())) {
    dofs = DofMap::make(mesh.num_nodes(), {});
    assembly = std::make_unique<ElasticAssembly>(mesh, make_cnh(16000, 120000, 1.0, 0.1), dofs);
    x = mesh.rest_positions();
    x.row(2) *= 0.9;
    x.row(0) *= 1.05;
  }
};

Ball& ball(long tets) {
  static std::map<long, std::unique_ptr<Ball>> cache;
  auto& b = cache[tets];
  if (!b) b = std::make_unique<Ball>(tets);
  return *b;
}

void BM_EnergyGradient(benchmark::State& state) {
  Ball& b = ball(state.range(0));
  omp_set_num_threads(static_cast<int>(state.range(1)));
  Eigen::VectorXd g;
  for (auto _ : state) benchmark::DoNotOptimize(b.assembly->gradient(b.x, g));
  state.counters["tets"] = b.mesh.num_tets();
  state.counters["tets_per_s"] = benchmark::Counter(static_cast<double>(b.mesh.num_tets()), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_EnergyGradientHessian(benchmark::State& state) {
  Ball& b = ball(state.range(0));
  omp_set_num_threads(static_cast<int>(state.range(1)));
  Eigen::VectorXd g;
  std::vector<double> values(b.assembly->pattern().nnz());
  for (auto _ : state) {
    std::fill(values.begin(), values.end(), 0.0);
    benchmark::DoNotOptimize(b.assembly->gradient(b.x, g));
    b.assembly->add_hessian(b.x, 1.0, values.data());
  }
  state.counters["tets"] = b.mesh.num_tets();
  state.counters["nnz"] = static_cast<double>(values.size());
  state.counters["tets_per_s"] = benchmark::Counter(static_cast<double>(b.mesh.num_tets()), benchmark::Counter::kIsIterationInvariantRate);
}
}  // namespace

BENCHMARK(BM_EnergyGradient)->Args({64000, 1})->Args({64000, 2})->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_EnergyGradientHessian)->Args({64000, 1})->Args({64000, 2})->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5)->ReportAggregatesOnly(true);
