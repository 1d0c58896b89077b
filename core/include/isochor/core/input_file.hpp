// Files a user names (scenes, meshes, surfaces, paint, motion, run files): opened only when they
// are regular files no larger than their format allows, so that a device (/dev/zero), a FIFO or
// a directory, or a file too large to be what it claims, is refused with one line before any of
// it is read.
#pragma once
#include <string>
#include <vector>

namespace isochor {

// Largest sizes accepted, per kind of file (bytes).
namespace input_limits {
constexpr double kScene = 64.0 * 1024 * 1024;         // TOML scenes and studies
constexpr double kMotion = 1024.0 * 1024 * 1024;      // BVH
constexpr double kSurface = 2048.0 * 1024 * 1024;     // STL, OBJ
constexpr double kPaint = 2048.0 * 1024 * 1024;       // PLY, OBJ, CSV paint
constexpr double kMesh = 16.0 * 1024 * 1024 * 1024;   // .msh, TetGen .node/.ele
constexpr double kRun = 1024.0 * 1024 * 1024 * 1024;  // HDF5 run files
}  // namespace input_limits

// Throws Error "PATH: no such file (expected WHAT)", "...: is a directory", "...: is a FIFO /
// a character device / ..., not a regular file", or "...: N MB, more than the M MB a WHAT may
// have", naming what was expected.
void check_input_file(const std::string& path, const std::string& what, double max_bytes);

// Before an output is written at `path`: where something is there already, it must be a regular
// file other than every file in `inputs` (the scene, its mesh, a run being exported...). Throws
// Error "PATH: is a directory / a FIFO / ..., not a regular file (expected a path for WHAT)" or
// "PATH: is the input INPUT (writing WHAT there would destroy it; expected another path)".
// Nothing there is fine (a new file); whether it may be replaced is the caller's rule.
void check_output_file(const std::string& path, const std::vector<std::string>& inputs, const std::string& what);

// The whole file, after check_input_file.
std::string read_input_file(const std::string& path, const std::string& what, double max_bytes);

}  // namespace isochor
