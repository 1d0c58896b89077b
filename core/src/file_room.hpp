// What the run-file writer asks of the file system before it writes: a lock on the output, the
// room on its disk and under the file size limit.
#pragma once
#include <string>

namespace isochor {

// An open-file-description lock on the open file `fd` (false: another writer holds it).
bool try_lock(int fd);
// Bytes free on the file system of `path`'s nearest existing directory; infinity where unknown.
double free_bytes(const std::string& path);
// The file size limit (ulimit -f) in bytes; infinity where unlimited.
double file_size_limit();
// Bytes as "N KB" for messages.
std::string kb(double bytes);

}  // namespace isochor
