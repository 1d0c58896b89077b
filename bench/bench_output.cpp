// Writing frames: N frames of a small box (4^3 cells) through OutputWriter, as a long animation
// writes them. Prints the frames per second of each tenth of the run and the resident memory at
// 10% and at the end: a frame must cost the same whether it is the 10th or the 100,000th.
//   build/isochor_bench_output [frames] [path]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "isochor/core/memory.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/core/output.hpp"

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 100000;
  const std::string path = argc > 2 ? argv[2] : "out/bench/output_frames.h5";
  isochor::Mesh mesh = isochor::make_box(Eigen::Vector3d::Ones(), {4, 4, 4}, Eigen::Vector3d::Zero(), 6);
  isochor::OutputWriter w(path, mesh, {}, {"", "bench", "bench"}, false);
  isochor::Points x = mesh.rest_positions();
  const int tenth = std::max(1, frames / 10);
  auto t0 = std::chrono::steady_clock::now();
  double rss10 = 0;
  std::printf("%d frames of %d nodes into %s\n%8s %12s\n", frames, mesh.num_nodes(), path.c_str(), "frames",
              "frames/s");
  for (int k = 0; k < frames; ++k) {
    x(2, 0) = 1e-6 * k;
    isochor::Frame f;
    f.time = 1e-3 * k;
    f.positions = &x;
    f.volumes = {1.0};
    f.stats = {{"steps", static_cast<double>(k)}};
    w.write_frame(f);
    if ((k + 1) % tenth == 0) {
      const auto t1 = std::chrono::steady_clock::now();
      std::printf("%8d %12.0f\n", k + 1, tenth / std::chrono::duration<double>(t1 - t0).count());
      std::fflush(stdout);
      t0 = t1;
      if (k + 1 == tenth) rss10 = isochor::resident_memory_mb();
    }
  }
  w.close();
  std::printf("resident memory: %.1f MB at 10%%, %.1f MB at the end\n", rss10, isochor::resident_memory_mb());
}
