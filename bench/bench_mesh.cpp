// Meshing and mesh-building cost: procedural box (adjacency, surface) and Gmsh spheres.
#include <benchmark/benchmark.h>

#include "isochor/core/meshing.hpp"

static void BM_Box(benchmark::State& state) {
  const long n = state.range(0);
  for (auto _ : state) {
    isochor::Mesh m = isochor::make_box(Eigen::Vector3d::Ones(), {n, n, n}, Eigen::Vector3d::Zero(), 6);
    benchmark::DoNotOptimize(m.num_tets());
    state.counters["tets"] = m.num_tets();
  }
}
BENCHMARK(BM_Box)->Arg(16)->Arg(32)->Unit(benchmark::kMillisecond);

static void BM_Sphere(benchmark::State& state) {
  for (auto _ : state) {
    isochor::Mesh m = isochor::make_sphere(0.1, 0.0, state.range(0), Eigen::Vector3d::Zero());
    state.counters["tets"] = m.num_tets();
  }
}
BENCHMARK(BM_Sphere)->Arg(4700)->Arg(64000)->Unit(benchmark::kMillisecond)->Iterations(1);
