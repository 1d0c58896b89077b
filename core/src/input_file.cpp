#include "isochor/core/input_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "isochor/base/error.hpp"

namespace isochor {

namespace {

const char* kind_of(mode_t m) {
  if (S_ISDIR(m)) return "a directory";
  if (S_ISFIFO(m)) return "a FIFO (named pipe)";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISSOCK(m)) return "a socket";
  return "not a regular file";
}

std::string megabytes(double bytes) {
  std::ostringstream s;
  s.precision(bytes < 10e6 ? 2 : 4);
  s << bytes / 1e6 << " MB";
  return s.str();
}

}  // namespace

void check_input_file(const std::string& path, const std::string& what, double max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) throw Error(path + ": no such file (expected " + what + ")");
    throw Error(path + ": cannot be read (" + std::strerror(errno) + "; expected " + what + ")");
  }
  if (S_ISDIR(st.st_mode)) throw Error(path + ": is a directory (expected " + what + ")");
  if (!S_ISREG(st.st_mode))
    throw Error(path + ": is " + kind_of(st.st_mode) + ", not a regular file (expected " + what + ")");
  const double size = static_cast<double>(st.st_size);
  if (size > max_bytes)
    throw Error(path + ": " + megabytes(size) + ", more than the " + megabytes(max_bytes) + " that " + what +
                " may have here");
}

void check_output_file(const std::string& path, const std::vector<std::string>& inputs, const std::string& what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;  // nothing there (or unreachable: the writer says why)
  if (!S_ISREG(st.st_mode))
    throw Error(path + ": is " + kind_of(st.st_mode) + ", not a regular file (expected a path for " + what + ")");
  for (const std::string& input : inputs) {
    struct stat in {};
    if (::stat(input.c_str(), &in) == 0 && in.st_dev == st.st_dev && in.st_ino == st.st_ino)
      throw Error(path + ": is the input " + input + " (writing " + what +
                  " there would destroy it; expected another path)");
  }
}

std::string read_input_file(const std::string& path, const std::string& what, double max_bytes) {
  check_input_file(path, what, max_bytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot be read (expected " + what + ")");
  std::ostringstream buf;
  buf << in.rdbuf();
  return buf.str();
}

}  // namespace isochor
