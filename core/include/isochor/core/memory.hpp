// The process's memory, for per-frame statistics and benchmarks (Linux).
#pragma once
#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

namespace isochor {

// Current resident set size in MB (/proc/self/statm); 0 where unavailable.
inline double resident_memory_mb() {
  std::ifstream in("/proc/self/statm");
  long pages = 0, resident = 0;
  if (!(in >> pages >> resident)) return 0.0;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// Peak resident set size in MB so far (getrusage).
inline double peak_memory_mb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}

// The memory a run may use, in MB: this machine's physical memory, or less if set (the fuzzer
// sets 200 MB, so that a scene asking for a large mesh is refused rather than meshed).
inline double& memory_budget_override_mb() {
  static double mb = 0;
  return mb;
}
inline void set_memory_budget_mb(double mb) { memory_budget_override_mb() = mb; }
inline double physical_memory_mb() {
  if (memory_budget_override_mb() > 0) return memory_budget_override_mb();
  return static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// What a run needs at least, to refuse before meshing what cannot fit (measured on the ball
// drop with IDA and KLU: 6.5 KB per tet from 16K to 64K tets over a baseline of about 80 MB of
// libraries; the krylov solver 6.4 KB per tet at 250K; Gmsh's meshes have about 5 V / h^3 tets
// for an edge length h, 4.8-4.9 for the sphere, cylinder and capsule).
constexpr double kBaselineMb = 80.0;
constexpr double kMinBytesPerTet = 4096.0;
constexpr double kGmshTetsPerEdgeCube = 4.0;  // a lower bound on tets per (V / h^3)

}  // namespace isochor
