// The XDMF sidecar of a run file: a header, one <Grid> per frame, a fixed tail. The first write
// replaces the file atomically (header and tail); each frame then overwrites the tail with its own
// <Grid> followed by the tail again, in one pwrite: the cost of a frame does not grow with the
// frames before it, and the file is complete after every frame (a killed run's sidecar lists every
// frame written, and a single write leaves no gap to be killed in).
#pragma once
#include <sys/types.h>

#include <string>
#include <vector>

namespace isochor {

// What a frame's <Grid> names: the run file (relative to the sidecar), the sizes, the per-node
// vectors of /frames/xdmf besides the position, whether /mesh/zone and pressures exist.
struct XdmfLayout {
  std::string h5_name;
  int nodes = 0, tets = 0;
  std::vector<std::string> node_vectors;
  bool zone = false, pressure = false;
};

class XdmfSidecar {
 public:
  XdmfSidecar() = default;
  XdmfSidecar(const XdmfSidecar&) = delete;
  XdmfSidecar& operator=(const XdmfSidecar&) = delete;
  ~XdmfSidecar() { close(); }
  // The sidecar at `path` with the <Grid>s of the frames at `times` (a resumed run's), opened for
  // the frames after them.
  void start(const std::string& path, const XdmfLayout& l, const std::vector<double>& times = {});
  // Frame k's <Grid>, where the tail was, and the tail after it (after start).
  void append(const XdmfLayout& l, int k, double time);
  void close();
  bool is_open() const { return fd_ >= 0; }
  static std::string grid(const XdmfLayout& l, int k, double time);

 private:
  std::string path_;
  int fd_ = -1;
  off_t tail_ = 0;
};

}  // namespace isochor
