#include "isochor/progress.hpp"

#include <unistd.h>

namespace isochor {

namespace {
std::string seconds(double s) {
  char buf[32];
  if (s < 120) std::snprintf(buf, sizeof buf, "%.1fs", s);
  else if (s < 7200) std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60);
  return buf;
}
}  // namespace

Progress::Progress(std::string label, int total_frames, std::FILE* out)
    : label_(std::move(label)), total_(total_frames), out_(out), tty_(out && isatty(fileno(out)) != 0) {
  start_ = last_ = std::chrono::steady_clock::now();
}

Progress::~Progress() { finish(); }

void Progress::update(int done, double sim_time) {
  const auto now = std::chrono::steady_clock::now();
  const double wall = std::chrono::duration<double>(now - start_).count();
  const double since = std::chrono::duration<double>(now - last_).count();
  if (!out_ || wall < 1.0) return;
  if (tty_ ? since < 0.1 : (since < 5.0 && shown_)) return;
  last_ = now;
  const double rest = done > 0 ? wall * (total_ - done) / done : 0.0;
  std::fprintf(out_, "%s%s: frame %d of %d, t = %.6g s, wall %s, about %s left%s", tty_ ? "\r" : "", label_.c_str(),
               done, total_, sim_time, seconds(wall).c_str(), seconds(rest).c_str(), tty_ ? "\033[K" : "\n");
  std::fflush(out_);
  shown_ = true;
}

void Progress::finish() {
  if (shown_ && tty_) std::fprintf(out_, "\n");
  shown_ = false;
}

}  // namespace isochor
