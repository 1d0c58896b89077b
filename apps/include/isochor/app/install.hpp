// Where the files that come with isochor lie. A build tree runs its tools from the source tree
// it was built from; a pip-installed package carries them beside its binaries (isochor/bin/isochor,
// isochor/_isochor*.so and isochor/tools/ in site-packages), so that it keeps working when the
// source and build trees are gone.
#pragma once
#include <filesystem>

namespace isochor {

// The tools folder (render.py, export.py, blender/, ...) for a binary in `own_dir`: own_dir/tools
// or own_dir/../tools when it holds render.py (an installed package), else `built_in`.
std::filesystem::path tools_directory(const std::filesystem::path& own_dir, const std::filesystem::path& built_in);

// The page of `isochor view` (viewer.js, index.html) for a binary in `own_dir`: own_dir/viewer or
// own_dir/../viewer when it holds viewer.js (an installed package), else `built_in`.
std::filesystem::path viewer_directory(const std::filesystem::path& own_dir, const std::filesystem::path& built_in);

// The command line for a module in `own_dir`: own_dir/bin/isochor when it is there (an installed
// package), else `built_in`.
std::filesystem::path executable_beside(const std::filesystem::path& own_dir, const std::filesystem::path& built_in);

// The folder of the running executable (/proc/self/exe).
std::filesystem::path this_executable_directory();

}  // namespace isochor
