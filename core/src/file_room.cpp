#include "file_room.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <filesystem>
#include <limits>

#include "isochor/base/error.hpp"

namespace isochor {

// The writer's lock on its output: an open-file-description lock (F_OFD_SETLK) on the file
// itself, held while the descriptor is open. Unlike flock (HDF5's own locking) and process-wide
// fcntl locks, HDF5 opening and closing the same file in this process does not release it.
bool try_lock(int fd) {
  struct flock l {};
  l.l_type = F_WRLCK;
  l.l_whence = SEEK_SET;
  return ::fcntl(fd, F_OFD_SETLK, &l) == 0;
}

// Bytes free on the file system of `path`'s nearest existing directory, and the file size
// limit (ulimit -f); infinity where unknown or unlimited.
double free_bytes(const std::string& path) {
  std::error_code ec;
  std::filesystem::path dir = std::filesystem::absolute(path, ec).parent_path();
  if (ec)  // a relative path, and the working directory was deleted under the program
    throw Error(path + ": cannot be placed (" + ec.message() +
                "; a relative path needs the working directory, which no longer exists: give an absolute path)");
  while (!dir.empty() && !std::filesystem::exists(dir, ec) && dir != dir.parent_path()) dir = dir.parent_path();
  struct statvfs fs {};
  if (::statvfs(dir.c_str(), &fs) != 0) return std::numeric_limits<double>::infinity();
  return static_cast<double>(fs.f_bavail) * static_cast<double>(fs.f_frsize);
}
double file_size_limit() {
  struct rlimit lim {};
  if (::getrlimit(RLIMIT_FSIZE, &lim) != 0 || lim.rlim_cur == RLIM_INFINITY)
    return std::numeric_limits<double>::infinity();
  return static_cast<double>(lim.rlim_cur);
}

std::string kb(double bytes) { return std::to_string(static_cast<long long>(bytes / 1024 + 0.5)) + " KB"; }

}  // namespace isochor
