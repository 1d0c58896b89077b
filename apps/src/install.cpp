#include "isochor/app/install.hpp"

#include <unistd.h>

namespace isochor {

namespace fs = std::filesystem;

namespace {

// own_dir/NAME or own_dir/../NAME when it holds `marker`, else built_in.
fs::path installed(const fs::path& own_dir, const char* name, const char* marker, const fs::path& built_in) {
  for (const fs::path& d : {own_dir / name, own_dir.parent_path() / name}) {
    std::error_code ec;
    if (fs::is_regular_file(d / marker, ec)) return d;
  }
  return built_in;
}

}  // namespace

fs::path tools_directory(const fs::path& own_dir, const fs::path& built_in) {
  return installed(own_dir, "tools", "render.py", built_in);
}

fs::path viewer_directory(const fs::path& own_dir, const fs::path& built_in) {
  return installed(own_dir, "viewer", "viewer.js", built_in);
}

fs::path executable_beside(const fs::path& own_dir, const fs::path& built_in) {
  const fs::path exe = own_dir / "bin" / "isochor";
  std::error_code ec;
  if (fs::is_regular_file(exe, ec) && ::access(exe.c_str(), X_OK) == 0) return exe;
  return built_in;
}

fs::path this_executable_directory() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

}  // namespace isochor
