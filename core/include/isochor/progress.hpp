// Progress of a long run: on a terminal one line rewritten in place (frame k of F, simulated
// time, wall time, estimate of the rest); otherwise plain log lines every few seconds. Nothing is
// shown for runs that finish within a second, or when `out` is null.
#pragma once
#include <chrono>
#include <cstdio>
#include <string>

namespace isochor {

class Progress {
 public:
  Progress(std::string label, int total_frames, std::FILE* out = stderr);
  ~Progress();
  void update(int frames_done, double sim_time);
  void finish();

 private:
  std::string label_;
  int total_;
  std::FILE* out_;
  bool tty_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace isochor
