// One error type for bad input and failed runs: its message is one line that names the file,
// key or element and what was expected. The command line prints it and exits non-zero.
#pragma once
#include <cstddef>
#include <stdexcept>
#include <string>

namespace isochor {

// A message quotes what the user gave (a path, a value, a line); a quote of megabytes would bury
// the line that explains it, so the middle of a message longer than this is left out, and the
// message says how much.
inline constexpr std::size_t kMaxMessageBytes = 2400;

inline std::string bounded_message(const std::string& message) {
  if (message.size() <= kMaxMessageBytes) return message;
  const std::size_t keep = (kMaxMessageBytes - 100) / 2;
  // Cut at the start of a UTF-8 character, never inside one.
  auto char_start = [&](std::size_t i) {
    while (i > 0 && (static_cast<unsigned char>(message[i]) & 0xC0) == 0x80) --i;
    return i;
  };
  const std::size_t head = char_start(keep);
  const std::size_t tail = char_start(message.size() - keep);
  std::string out(message, 0, head);
  out.append(" [... ").append(std::to_string(tail - head)).append(" bytes left out ...] ");
  out.append(message, tail, std::string::npos);
  return out;
}

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(bounded_message(message)) {}
};

}  // namespace isochor
