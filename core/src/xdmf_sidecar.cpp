#include "xdmf_sidecar.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "hdf5_util.hpp"
#include "isochor/base/error.hpp"

namespace isochor {
namespace {
constexpr const char* kXdmfTail = "  </Grid>\n </Domain>\n</Xdmf>\n";
}  // namespace

std::string XdmfSidecar::grid(const XdmfLayout& l, int k, double time) {
  std::ostringstream x;
  x.precision(17);
  const std::string f = h5::frame_name(k);
  x << "   <Grid Name=\"frame_" << f << "\" GridType=\"Uniform\">\n"
    << "    <Time Value=\"" << time << "\"/>\n"
    << "    <Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"" << l.tets << "\">\n"
    << "     <DataItem Dimensions=\"" << l.tets << " 4\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">"
    << l.h5_name << ":/mesh/tets</DataItem>\n    </Topology>\n"
    << "    <Geometry GeometryType=\"XYZ\">\n"
    << "     <DataItem Dimensions=\"" << l.nodes << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
    << l.h5_name << ":/frames/xdmf/position_" << f << "</DataItem>\n    </Geometry>\n"
    << "    <Attribute Name=\"position\" AttributeType=\"Vector\" Center=\"Node\">\n"
    << "     <DataItem Dimensions=\"" << l.nodes << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
    << l.h5_name << ":/frames/xdmf/position_" << f << "</DataItem>\n    </Attribute>\n";
  for (const std::string& name : l.node_vectors)
    x << "    <Attribute Name=\"" << name << "\" AttributeType=\"Vector\" Center=\"Node\">\n"
      << "     <DataItem Dimensions=\"" << l.nodes << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
      << l.h5_name << ":/frames/xdmf/" << name << "_" << f << "</DataItem>\n    </Attribute>\n";
  if (l.zone)
    x << "    <Attribute Name=\"zone\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
      << "     <DataItem Dimensions=\"" << l.tets << "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">"
      << l.h5_name << ":/mesh/zone</DataItem>\n    </Attribute>\n";
  if (l.pressure)
    x << "    <Attribute Name=\"pressure\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
      << "     <DataItem Dimensions=\"" << l.tets << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
      << l.h5_name << ":/frames/xdmf/pressure_" << f << "</DataItem>\n    </Attribute>\n";
  x << "   </Grid>\n";
  return x.str();
}

// The header, the <Grid>s of the frames already in the file (`times`: a resumed run's) and the
// tail, written to a temporary file and renamed over the sidecar.
void XdmfSidecar::start(const std::string& path, const XdmfLayout& l, const std::vector<double>& times) {
  close();
  path_ = path;
  const std::string header =
      "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
      "  <Grid Name=\"isochor\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  const std::string &xp = path_, tmp = path_ + ".tmp";
  off_t size = static_cast<off_t>(header.size());
  {
    std::ofstream out(tmp);
    out << header;
    for (std::size_t k = 0; k < times.size(); ++k) {
      const std::string g = grid(l, static_cast<int>(k), times[k]);
      out << g;
      size += static_cast<off_t>(g.size());
    }
    out << kXdmfTail;
    if (!out) {
      std::filesystem::remove(tmp);
      throw Error(xp + ": cannot be written (" + std::strerror(errno) + ")");
    }
  }
  std::filesystem::rename(tmp, xp);
  fd_ = ::open(xp.c_str(), O_WRONLY);
  if (fd_ < 0) throw Error(xp + ": cannot be opened for writing");
  tail_ = size;
}

// Frame k's <Grid>, where the tail was, and the tail after it.
void XdmfSidecar::append(const XdmfLayout& l, int k, double time) {
  const std::string block = grid(l, k, time) + kXdmfTail;
  if (::pwrite(fd_, block.data(), block.size(), tail_) != static_cast<ssize_t>(block.size()))
    throw Error(path_ + ": cannot be written (frame " + std::to_string(k) + ")");
  tail_ += static_cast<off_t>(block.size() - std::char_traits<char>::length(kXdmfTail));
}

void XdmfSidecar::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

}  // namespace isochor
