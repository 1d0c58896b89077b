// One error type for bad input and failed runs: its message is one line that names the file,
// key or element and what was expected. The command line prints it and exits non-zero.
#pragma once
#include <stdexcept>
#include <string>

namespace isochor {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace isochor
