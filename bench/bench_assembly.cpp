// Assembly throughput on a sphere: tets per second for energy + gradient, for energy + gradient +
// Hessian fill into the fixed pattern in one pass (what a Newton step asks) and in two, on 1 and 2
// threads (argument 2); the bytes each pass must move, against the machine's read bandwidth.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <memory>

#include <map>
#include <vector>

#include "isochor/models/assembly.hpp"
#include "isochor/core/meshing.hpp"

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

// Bytes a pass must move at the least, per tet: each tet's nodes and shape (read in sequence),
// every node's position read and gradient read and written once; with the Hessian, each tet's
// 144 slots and every matrix entry read and written once. Against the machine's read bandwidth
// (BM_ReadBandwidth) this says how close a pass is to being memory-bound.
double bytes_per_tet(const Ball& b, bool hessian) {
  const double T = b.mesh.num_tets(), N = b.mesh.num_nodes();
  double bytes = T * (sizeof(Tet) + sizeof(TetShape)) + N * 3 * 8 * 3;
  if (hessian) bytes += T * 144 * sizeof(Index) + 2.0 * 8 * static_cast<double>(b.assembly->pattern().nnz());
  return bytes / T;
}

void set_counters(benchmark::State& state, const Ball& b, bool hessian) {
  state.counters["tets"] = b.mesh.num_tets();
  state.counters["tets_per_s"] =
      benchmark::Counter(static_cast<double>(b.mesh.num_tets()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["bytes_per_tet"] = bytes_per_tet(b, hessian);
  state.counters["bytes_per_s"] =
      benchmark::Counter(bytes_per_tet(b, hessian) * b.mesh.num_tets(), benchmark::Counter::kIsIterationInvariantRate,
                         benchmark::Counter::kIs1024);
}

// One thread reading 512 MB of doubles in sequence: the bandwidth a streaming pass could reach.
void BM_ReadBandwidth(benchmark::State& state) {
  static const std::vector<double> data(64 << 20, 1.0);
  for (auto _ : state) {
    double sum = 0;
    for (double d : data) sum += d;
    benchmark::DoNotOptimize(sum);
  }
  state.counters["bytes_per_s"] =
      benchmark::Counter(8.0 * data.size(), benchmark::Counter::kIsIterationInvariantRate, benchmark::Counter::kIs1024);
}

void BM_EnergyGradient(benchmark::State& state) {
  Ball& b = ball(state.range(0));
  omp_set_num_threads(static_cast<int>(state.range(1)));
  Eigen::VectorXd g;
  for (auto _ : state) benchmark::DoNotOptimize(b.assembly->gradient(b.x, g));
  set_counters(state, b, false);
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
  set_counters(state, b, true);
}

// What a Newton step asks: energy, gradient and Hessian in one pass over the elements.
void BM_OnePassGradientHessian(benchmark::State& state) {
  Ball& b = ball(state.range(0));
  omp_set_num_threads(static_cast<int>(state.range(1)));
  Eigen::VectorXd g(3 * b.mesh.num_nodes());
  std::vector<double> values(b.assembly->pattern().nnz());
  for (auto _ : state) {
    std::fill(values.begin(), values.end(), 0.0);
    g.setZero();
    ElementPass p;
    p.grad = &g;
    p.values = values.data();
    benchmark::DoNotOptimize(b.assembly->evaluate(b.x, p));
  }
  set_counters(state, b, true);
}
}  // namespace

BENCHMARK(BM_EnergyGradient)
    ->Args({64000, 1})
    ->Args({64000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_ReadBandwidth)->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_OnePassGradientHessian)
    ->Args({64000, 1})
    ->Args({64000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_EnergyGradientHessian)
    ->Args({64000, 1})
    ->Args({64000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
