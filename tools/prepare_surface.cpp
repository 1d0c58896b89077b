// isochor_prepare_surface: a scanned surface made ready for Gmsh to fill with tets.
//
//   isochor_prepare_surface IN OUT.obj [--wrap A] [--offset O] [--faces N] [--length L]
//
// Scanned models often intersect themselves (the Stanford dragon's decimated copy does), and Gmsh
// cannot fill a self-intersecting surface. --wrap A replaces the surface by CGAL's 3D alpha wrap
// (alpha = diagonal / A, offset = diagonal / O, default 1000): closed, 2-manifold and free of
// self-intersections by construction, a little outside the input. --faces N then collapses edges
// (Garland-Heckbert quadrics, positions bounded so that no face flips) down to about N faces.
// --length L scales the result so that its bounding box's longest side is L (metres). The output
// is checked closed and free of self-intersections; a surface that is not stops with one line.
// OUT is written whole or not at all: a full disk or a file size limit leaves no partial file.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_placement.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <CGAL/alpha_wrap_3.h>

#include <cctype>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Surface = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;
namespace SMS = CGAL::Surface_mesh_simplification;

struct Options {
  std::string in, out;
  double wrap = 0, offset = 1000, length = 0;
  long faces = 0;
};

[[noreturn]] void fail(const std::string& what) {
  std::cerr << "isochor_prepare_surface: " << what << "\n";
  std::exit(1);
}

double positive_number(const std::string& key, const char* text) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !(v > 0) || !std::isfinite(v))
    fail(key + " " + text + ": expected a positive number");
  return v;
}

// OUT's extension, lower case, when it is a format this tool writes; else it stops.
std::string output_format(const std::string& out) {
  std::string ext = std::filesystem::path(out).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    fail(out + ": expected an output file ending in .obj, .off, .ply or .stl");
  return ext;
}

// OUT in its format, written to STEM.part.EXT beside it and renamed into place; a write that fails
// (SIGXFSZ is ignored, so a file size limit fails the write instead of killing the process)
// removes the part file and stops with one line.
void write_whole(const std::string& out, const Surface& s) {
  namespace fs = std::filesystem;
  const std::string ext = output_format(out);
  const fs::path path(out);
  const fs::path part = path.parent_path() / (path.stem().string() + ".part" + path.extension().string());
  bool ok = false;
  {
    std::ofstream f(part, std::ios::binary);
    const auto np = CGAL::parameters::stream_precision(9);
    if (f) {
      if (ext == ".obj") ok = CGAL::IO::write_OBJ(f, s, np);
      if (ext == ".off") ok = CGAL::IO::write_OFF(f, s, np);
      if (ext == ".ply") ok = CGAL::IO::write_PLY(f, s, np);
      if (ext == ".stl") ok = CGAL::IO::write_STL(f, s, np);
      f.close();
      ok = ok && !f.fail();
    }
  }
  std::error_code ec;
  if (ok) fs::rename(part, path, ec);
  if (!ok || ec) {
    fs::remove(part, ec);
    fail(out + ": cannot be written (a full disk, a file size limit or no permission?); nothing was written");
  }
}

Options parse(int argc, char** argv) {
  Options o;
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if ((a == "--wrap" || a == "--offset" || a == "--faces" || a == "--length") && !has_value)
      fail(a + ": expected a value after it");
    if (a == "--wrap")
      o.wrap = positive_number(a, argv[++i]);
    else if (a == "--offset")
      o.offset = positive_number(a, argv[++i]);
    else if (a == "--faces")
      o.faces = std::lround(positive_number(a, argv[++i]));
    else if (a == "--length")
      o.length = positive_number(a, argv[++i]);
    else if (!a.empty() && a[0] == '-')
      fail(a + ": unknown option (expected --wrap, --offset, --faces or --length)");
    else if (positional++ == 0)
      o.in = a;
    else if (positional == 2)
      o.out = a;
    else
      fail(a + ": one input and one output expected");
  }
  if (o.out.empty()) fail("usage: isochor_prepare_surface IN OUT.obj [--wrap A] [--offset O] [--faces N] [--length L]");
  return o;
}

double diagonal(const Surface& s) {
  const auto b = PMP::bbox(s);
  return std::sqrt(CGAL::square(b.xmax() - b.xmin()) + CGAL::square(b.ymax() - b.ymin()) +
                   CGAL::square(b.zmax() - b.zmin()));
}

void collapse_to(Surface& s, long faces) {
  using Policies = SMS::GarlandHeckbert_plane_policies<Surface, Kernel>;
  Policies policies(s);
  SMS::Bounded_normal_change_placement<Policies::Get_placement> placement(policies.get_placement());
  SMS::Count_stop_predicate<Surface> stop(static_cast<std::size_t>(faces) * 3 / 2);  // edges = 3/2 faces, closed
  SMS::edge_collapse(s, stop, CGAL::parameters::get_cost(policies.get_cost()).get_placement(placement));
  s.collect_garbage();
}

void scale_to(Surface& s, double length) {
  const auto b = PMP::bbox(s);
  const double longest = std::max({b.xmax() - b.xmin(), b.ymax() - b.ymin(), b.zmax() - b.zmin()});
  const double k = length / longest;
  for (auto v : s.vertices()) {
    const auto& p = s.point(v);
    s.point(v) = Kernel::Point_3(p.x() * k, p.y() * k, p.z() * k);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGXFSZ, SIG_IGN);
  const Options o = parse(argc, argv);
  output_format(o.out);  // before any work
  Surface s;
  if (!PMP::IO::read_polygon_mesh(o.in, s) || s.number_of_faces() == 0)
    fail(o.in + ": cannot be read as a triangle surface (expected .obj, .off, .ply or .stl)");
  const std::size_t faces_in = s.number_of_faces();
  const bool crossed = PMP::does_self_intersect(s);
  if (o.wrap > 0) {
    const double d = diagonal(s);
    Surface wrapped;
    CGAL::alpha_wrap_3(s, d / o.wrap, d / o.offset, wrapped);
    s = std::move(wrapped);
  }
  if (o.faces > 0 && static_cast<long>(s.number_of_faces()) > o.faces) collapse_to(s, o.faces);
  if (o.length > 0) scale_to(s, o.length);
  if (!CGAL::is_closed(s)) fail(o.out + ": the result is not closed (wrap it: --wrap 80)");
  if (PMP::does_self_intersect(s))
    fail(o.out + ": the result intersects itself (wrap it with --wrap, or keep more faces)");
  write_whole(o.out, s);
  std::printf("%s: %zu faces%s -> %s: %zu faces, %zu vertices, closed, no self-intersection\n", o.in.c_str(), faces_in,
              crossed ? " (intersecting itself)" : "", o.out.c_str(), static_cast<std::size_t>(s.number_of_faces()),
              static_cast<std::size_t>(s.number_of_vertices()));
  return 0;
}
