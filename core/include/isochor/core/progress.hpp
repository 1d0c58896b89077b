// Progress of a long run: on a terminal one line rewritten in place (frame k of F, simulated
// time, wall time, estimate of the rest); otherwise plain log lines every few seconds, and at
// least every 30 s even when no frame is finished (the time the steps have reached, from
// `step_time`). The estimate extrapolates the recent rate of simulated time per wall second (the
// last fifth of the run, at least 10 s of it), not the average since the start: a run whose
// steps shrink (an impact) is not promised the pace of its easy beginning. Nothing is shown for
// runs that finish within a second, or when `out` is null.
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace isochor {

// Seconds left at the recent rate: `samples` are (wall seconds, simulated time), oldest first;
// the rate is taken over the samples of the last max(10 s, wall / 5); the run ends at t_end.
// Negative when there is no rate yet.
double remaining_seconds(const std::deque<std::pair<double, double>>& samples, double t_end);

// A duration as the progress line writes it: 12.3s, 4m05s, 3h07m; over 1000 hours (a run whose
// steps have all but stopped), "over 1000h" rather than a number that overflows.
std::string duration_text(double seconds);

class Progress {
 public:
  Progress(std::string label, int total_frames, double t0, double t_end, std::FILE* out = stderr,
           std::function<double()> step_time = nullptr);
  ~Progress();
  void update(int frames_done, double sim_time);
  void finish();
  // The longest silence of a log between frames (30 s).
  void set_heartbeat(double seconds) { heartbeat_ = seconds; }

 private:
  void print(double wall, const char* what, double sim_time);  // with mutex_ held
  void heartbeat();

  std::string label_;
  int total_, done_ = 0;
  double t_end_;
  std::FILE* out_;
  bool tty_;
  bool shown_ = false;
  std::function<double()> step_time_;
  std::chrono::steady_clock::time_point start_, last_;
  std::deque<std::pair<double, double>> samples_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  double heartbeat_ = 30.0;
  std::thread thread_;
};

}  // namespace isochor
