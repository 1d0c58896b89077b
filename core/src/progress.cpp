#include "isochor/core/progress.hpp"

#include <unistd.h>

#include <cmath>

namespace isochor {

std::string duration_text(double s) {
  char buf[32];
  if (!(s < 3.6e6)) return "over 1000h";
  if (s < 120)
    std::snprintf(buf, sizeof buf, "%.1fs", s);
  else if (s < 7200)
    std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else
    std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60);
  return buf;
}

double remaining_seconds(const std::deque<std::pair<double, double>>& samples, double t_end) {
  if (samples.size() < 2) return -1;
  const auto& [wall, t] = samples.back();
  const double window = std::max(10.0, wall / 5);
  auto first = samples.begin();
  while (std::next(first) != samples.end() && wall - std::next(first)->first >= window) ++first;
  const double dw = wall - first->first, dt = t - first->second;
  if (dw <= 0 || dt <= 0) return -1;
  return std::max(0.0, t_end - t) * dw / dt;
}

Progress::Progress(std::string label, int total_frames, double t0, double t_end, std::FILE* out,
                   std::function<double()> step_time)
    : label_(std::move(label)),
      total_(total_frames),
      t_end_(t_end),
      out_(out),
      tty_(out && isatty(fileno(out)) != 0),
      step_time_(std::move(step_time)) {
  start_ = last_ = std::chrono::steady_clock::now();
  samples_.emplace_back(0.0, t0);
  if (out_) thread_ = std::thread([this] { heartbeat(); });
}

Progress::~Progress() { finish(); }

void Progress::print(double wall, const char* what, double sim_time) {
  last_ = std::chrono::steady_clock::now();
  const double rest = remaining_seconds(samples_, t_end_);
  std::fprintf(out_, "%s%s: %s%d of %d, t = %.6g s, wall %s, %s%s", tty_ ? "\r" : "", label_.c_str(), what, done_,
               total_, sim_time, duration_text(wall).c_str(),
               rest < 0 ? "estimating" : ("about " + duration_text(rest) + " left").c_str(), tty_ ? "\033[K" : "\n");
  std::fflush(out_);
  shown_ = true;
}

void Progress::update(int done, double sim_time) {
  const auto now = std::chrono::steady_clock::now();
  const double wall = std::chrono::duration<double>(now - start_).count();
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = done;
  samples_.emplace_back(wall, sim_time);
  // Samples older than the rate's window are not needed (keep one before it).
  while (samples_.size() > 2 && wall - samples_[1].first > std::max(10.0, wall / 5)) samples_.pop_front();
  const double since = std::chrono::duration<double>(now - last_).count();
  if (!out_ || wall < 1.0) return;
  if (tty_ ? since < 0.1 : (since < 5.0 && shown_)) return;
  print(wall, "frame ", sim_time);
}

// Between frames: a line at least every 30 s (a terminal: every second) with the time the steps
// have reached.
void Progress::heartbeat() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    wake_.wait_for(lock, std::chrono::milliseconds(250));
    if (stop_) break;
    const auto now = std::chrono::steady_clock::now();
    const double wall = std::chrono::duration<double>(now - start_).count();
    const double since = std::chrono::duration<double>(now - last_).count();
    if (wall < 1.0 || since < (tty_ ? 1.0 : heartbeat_)) continue;
    const double t = step_time_ ? step_time_() : std::nan("");
    if (std::isfinite(t) && t > samples_.back().second) samples_.emplace_back(wall, t);
    print(wall, "steps past frame ", std::isfinite(t) ? t : samples_.back().second);
  }
}

void Progress::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (shown_ && tty_) std::fprintf(out_, "\n");
  shown_ = false;
}

}  // namespace isochor
