#include "isochor/scene/zones_setup.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdio>
#include <limits>
#include <set>

#include "isochor/base/error.hpp"
#include "isochor/core/paint.hpp"
#include "isochor/core/selection.hpp"
#include "isochor/models/constraints.hpp"

namespace isochor {

namespace {

// Checks a new zone's name: non-empty, no '/', '.' or ',', not defined before.
void check_zone_name(const Section& z, std::string_view key, const std::string& name,
                     const std::vector<std::pair<std::string, std::vector<int>>>& zones) {
  if (name.empty()) z.fail(key, "missing, expected a zone name");
  if (name.find_first_of("/.,") != std::string::npos) z.fail(key, "expected a name without '/', '.' or ','");
  for (const auto& other : zones)
    if (other.first == name) z.fail(key, "zone \"" + name + "\" is defined twice");
}

// Zones painted by the mesh file's own surface groups (Gmsh 2-D physical groups, node sets of
// the mesh): `groups = [names]`, each a zone of that name, its paint 1 on the group's nodes.
void parse_group_paint(const Section& p, const Mesh& mesh,
                       std::vector<std::pair<std::string, std::vector<int>>>& zones) {
  for (const char* key : {"file", "labels", "colors", "weights", "property"})
    if (p.has(key)) p.fail(key, "not with groups (the mesh's surface groups are the paint)");
  const std::vector<std::string> groups = p.strings("groups");
  if (groups.empty()) p.fail("groups", "expected a list of the mesh's surface groups, e.g. [\"belly\", \"back\"]");
  const std::vector<int>& nodes = mesh.surface_nodes();
  PaintedPoints painted;
  painted.path = "the mesh's groups";
  painted.x.resize(3, static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i) painted.x.col(i) = mesh.rest_positions().col(nodes[i]);
  std::vector<std::vector<double>> membership;
  for (const std::string& g : groups) {
    check_zone_name(p, "groups", g, zones);
    const auto it = mesh.node_sets.find(g);
    if (it == mesh.node_sets.end()) {
      std::string known;
      for (const auto& [name, set] : mesh.node_sets) known += (known.empty() ? "" : ", ") + name;
      p.fail("groups", "the mesh has no group \"" + g + "\" (its groups: " + (known.empty() ? "none" : known) + ")");
    }
    std::vector<double> m(nodes.size(), 0.0);
    for (std::size_t i = 0; i < nodes.size(); ++i)
      m[i] = std::binary_search(it->second.begin(), it->second.end(), nodes[i]);
    membership.push_back(std::move(m));
  }
  std::vector<std::vector<int>> tets =
      painted_zones(mesh, painted, membership, std::numeric_limits<double>::infinity());
  for (std::size_t z = 0; z < groups.size(); ++z) {
    if (tets[z].empty())
      p.fail("groups", "no tet is painted by group \"" + groups[z] + "\" (expected a group of surface triangles)");
    zones.emplace_back(groups[z], std::move(tets[z]));
  }
}

// [[zones.paint]]: zones painted on the surface (paint.hpp), one per entry of labels, colors or
// weights, or one per surface group of the mesh.
void parse_paint(const Section& p, const Mesh& mesh, const SceneFile& file,
                 std::vector<std::pair<std::string, std::vector<int>>>& zones) {
  if (p.has("groups")) return parse_group_paint(p, mesh, zones);
  if (!p.has("file"))
    p.fail("file", "missing, expected a paint file (.ply, .obj or .csv) or the mesh's surface groups (groups)");
  const std::string path = file.resolve_path(p.string("file", ""));
  PaintRule rule;
  const int given = p.has("labels") + p.has("colors") + p.has("weights");
  if (given != 1)
    p.fail(given ? "colors" : "labels", "expected exactly one of labels, colors or weights (a table from zone names)");
  const char* key = p.has("labels") ? "labels" : p.has("colors") ? "colors" : "weights";
  rule.by = p.has("labels") ? PaintRule::By::labels : p.has("colors") ? PaintRule::By::colors : PaintRule::By::weights;
  const Section t = p.table(key);
  if (!t.exists() || t.keys().empty()) p.fail(key, "expected a table from zone names, e.g. { belly = 1, back = 2 }");
  for (const std::string& name : t.keys()) {
    check_zone_name(t, name, name, zones);
    rule.zones.push_back(name);
    if (rule.by == PaintRule::By::labels) {
      rule.labels.push_back(t.integer(name, 0));
    } else if (rule.by == PaintRule::By::colors) {
      const std::vector<double> c = t.numbers(name);
      if (c.size() != 3) t.fail(name, "expected a colour [r, g, b] (0..1, or 0..255)");
      Eigen::Vector3d v(c[0], c[1], c[2]);
      if (v.maxCoeff() > 1) v /= 255.0;
      rule.colors.push_back(v);
    } else {
      rule.weights.push_back(t.string(name, ""));
    }
  }
  rule.property = p.string("property");
  rule.color_tolerance = p.number("color_tolerance");
  const Points& X = mesh.rest_positions();
  const double diagonal = (X.rowwise().maxCoeff() - X.rowwise().minCoeff()).norm();
  const double tolerance = p.number("tolerance", 0.02 * diagonal);
  const std::string disconnected = p.string("disconnected");
  std::vector<std::vector<int>> tets;
  try {
    const PaintedPoints painted = read_paint(path, &X);
    tets = painted_zones(mesh, painted, paint_membership(painted, rule), tolerance);
  } catch (const Error& e) {
    p.fail("file", e.what());
  }
  for (std::size_t z = 0; z < rule.zones.size(); ++z) {
    if (tets[z].empty())
      t.fail(rule.zones[z], "no tet is painted " + rule.zones[z] + " (expected some painted vertex with this paint)");
    auto pieces = connected_pieces(mesh, tets[z]);
    if (pieces.size() > 1 && disconnected == "error")
      t.fail(rule.zones[z],
             "zone \"" + rule.zones[z] + "\" is painted in " + std::to_string(pieces.size()) +
                 " disconnected pieces (of " + std::to_string(pieces[0].size()) + ", " +
                 std::to_string(pieces[1].size()) + (pieces.size() > 2 ? ", ..." : "") +
                 " tets): paint each piece as its own zone, or set disconnected = \"keep\" or \"split\"");
    if (pieces.size() > 1 && disconnected == "split") {
      for (std::size_t k = 0; k < pieces.size(); ++k) {
        std::sort(pieces[k].begin(), pieces[k].end());
        zones.emplace_back(rule.zones[z] + "_" + std::to_string(k + 1), std::move(pieces[k]));
      }
    } else {
      zones.emplace_back(rule.zones[z], std::move(tets[z]));
    }
  }
}

}  // namespace

ZoneChoice parse_zones(const Section& s, const Mesh& mesh, const SceneFile& file, bool cnh) {
  ZoneChoice c;
  auto& zones = c.zones;
  // CNH's choice when the table names no zone: patches the size of a 2-ring, not the global zone
  // (which resists no local change of volume: a mechanism in bending without the penalty, and
  // locking with a large one; docs/results/infsup). A table that names zones keeps the paper's
  // global zone on top unless it says otherwise, or names patches (whose sum it would repeat).
  bool named = false;
  for (const char* key : {"global", "rings", "patches", "from_mesh", "paint", "zone"}) named = named || s.has(key);
  // zones.default: the paper's choice by name, for scenes that switch models by --set (UNH and
  // SNH get no zones unless the table names them).
  const bool paper = s.string("default") == "global";
  c.automatic = cnh && !named && !paper;
  if (s.boolean("global", cnh && (paper || (named && !s.has("patches"))))) {
    std::vector<int> all(mesh.num_tets());
    for (int e = 0; e < mesh.num_tets(); ++e) all[e] = e;
    zones.emplace_back("global", std::move(all));
  }
  if (const long k = s.integer("rings"); k > 0) {
    // One zone per node: the tets of its k-ring (Irving et al. 2007 for k = 1).
    const DofMap all = DofMap::make(mesh.num_nodes(), {});
    // Nodes whose rings hold the same tets (large k on a small mesh) give one zone, not
    // several identical constraints (which would make the KKT matrix singular).
    const auto rings = ring_zones(mesh, static_cast<int>(k), all);
    std::set<std::vector<int>> seen;
    for (std::size_t v = 0; v < rings.size(); ++v)
      if (seen.insert(rings[v]).second)
        zones.emplace_back("ring" + std::to_string(k) + "_" + std::to_string(v), rings[v]);
  }
  c.patches_begin = zones.size();
  if (const long k = s.integer("patches", c.automatic ? kDefaultPatchRings : 0); k > 0) {
    c.patch_rings = static_cast<int>(k);
    const auto patches = patch_zones(mesh, static_cast<int>(k));
    for (std::size_t p = 0; p < patches.size(); ++p)
      zones.emplace_back("patch" + std::to_string(k) + "_" + std::to_string(p), patches[p]);
  }
  c.generated = zones.size();
  if (s.boolean("from_mesh", false))
    for (const auto& [name, tets] : mesh.zones) zones.emplace_back(name, tets);
  for (const Section& p : s.tables("paint")) parse_paint(p, mesh, file, zones);
  for (const Section& z : s.tables("zone")) {
    const std::string name = z.string("name", "");
    check_zone_name(z, "name", name, zones);
    Section sel = z.table("select");
    if (!sel.exists())
      z.fail("select", "missing, expected a selection such as { kind = \"box\", min = [..], max = [..] }");
    zones.emplace_back(name, select_tets(mesh, Selection::parse(sel)));
  }
  return c;
}

ZonesAcross zones_across(const Mesh& mesh, const std::vector<std::pair<std::string, std::vector<int>>>& zones) {
  const Points& X = mesh.rest_positions();
  const Eigen::Vector3d mean = X.rowwise().mean();
  const Points Y = X.colwise() - mean;
  // The principal directions, the smallest spread first.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(Y * Y.transpose());
  const Eigen::Matrix3Xd P = es.eigenvectors().transpose() * Y;  // rows: coordinates along each direction
  ZonesAcross r;
  r.extent = P.rowwise().maxCoeff() - P.rowwise().minCoeff();
  Eigen::Vector3d zone_extent = Eigen::Vector3d::Zero();
  for (const auto& [name, tets] : zones) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int e : tets)
      for (int n : mesh.tets()[e]) {
        lo = lo.cwiseMin(P.col(n));
        hi = hi.cwiseMax(P.col(n));
      }
    zone_extent += hi - lo;
  }
  zone_extent /= static_cast<double>(std::max<std::size_t>(1, zones.size()));
  r.across = r.extent.cwiseQuotient(zone_extent.cwiseMax(1e-300));
  return r;
}

namespace {

// A zone whose every tet has its four nodes driven (by boundaries or bones) has a zero
// constraint row: generated ones are dropped, a named one is an error.
void drop_driven_zones(const Section& s, ZoneChoice& c, const Mesh& mesh, const std::vector<int>& driven_nodes) {
  std::vector<char> driven(mesh.num_nodes(), 0);
  for (int n : driven_nodes) driven[n] = 1;
  ZoneChoice kept = c;
  kept.zones.clear();
  kept.patches_begin = kept.generated = 0;
  for (std::size_t j = 0; j < c.zones.size(); ++j) {
    const auto& [name, tets] = c.zones[j];
    const bool moves = std::any_of(tets.begin(), tets.end(), [&](int e) {
      const Tet& t = mesh.tets()[e];
      return !(driven[t[0]] && driven[t[1]] && driven[t[2]] && driven[t[3]]);
    });
    if (!moves && j >= c.generated)
      s.fail("zone", "zone \"" + name +
                         "\": every node of its tets is driven (by [[boundary]] or bones), so no free node keeps its "
                         "volume (expected a zone with free nodes)");
    if (!moves) continue;
    kept.patches_begin += j < c.patches_begin;
    kept.generated += j < c.generated;
    kept.zones.push_back(std::move(c.zones[j]));
  }
  c = std::move(kept);
}

// Zones whose volumes follow exactly from the others' get no constraint row; the scene says so.
// An elimination beyond kRedundancyWork entries is not finished, and every zone keeps its row:
// 1-ring zones on the 21,870-tet beam take 25M (0.2 s, 70 MB), on 101,250 tets 309M (2 s, 1 GB);
// a partition (patches, mesh regions) takes one pass over its tets, the global zone over it about
// tets x zones / 2 (1.2M for the beam's 108 patches).
constexpr std::size_t kRedundancyWork = 40'000'000;

void note_redundant_zones(Scene& sc) {
  sc.redundant_zones.clear();
  if (sc.zones.size() < 2 || !sc.keep_zones) return;
  std::vector<std::vector<int>> tets;
  for (const auto& z : sc.zones) tets.push_back(z.second);
  const auto redundant = redundant_zones(tets, kRedundancyWork);
  if (!redundant || redundant->empty()) return;
  sc.redundant_zones = *redundant;
  std::string names;
  for (std::size_t k = 0; k < redundant->size() && k < 3; ++k)
    names += (k ? ", " : "") + sc.zones[static_cast<std::size_t>((*redundant)[k])].first;
  if (redundant->size() > 3) names += ", ...";
  sc.notes.push_back("zones: " + std::to_string(redundant->size()) + " of " + std::to_string(sc.zones.size()) +
                     " zones (" + names +
                     ") hold volumes that are sums and differences of the other zones' at every shape: they are "
                     "kept exactly by the others' constraints and get no constraint row of their own");
}

}  // namespace

void settle_zones(const Section& s, ZoneChoice c, Scene& sc) {
  if (const std::vector<int> driven = sc.driven_nodes(); !driven.empty()) drop_driven_zones(s, c, sc.mesh, driven);
  if (c.patch_rings > 0 && c.zones.size() > 1) {
    const ZonesAcross a = zones_across(sc.mesh, {c.zones.begin() + static_cast<std::ptrdiff_t>(c.patches_begin),
                                                 c.zones.begin() + static_cast<std::ptrdiff_t>(c.generated)});
    if (a.across(0) < 2) {
      char buf[400];
      std::snprintf(buf, sizeof buf,
                    "zones: %d-ring patches are %.1f across the body's thinnest direction (%.3g m; %.1f and %.1f "
                    "across the others): bending across it is held by the local penalty (material.lambda) more "
                    "than by the zones; refine the mesh to at least two patches across (docs/scenes.md, [zones])",
                    c.patch_rings, a.across(0), a.extent(0), a.across(1), a.across(2));
      sc.notes.emplace_back(buf);
    }
  }
  const bool local = std::any_of(c.zones.begin(), c.zones.end(), [](const auto& z) { return z.first != "global"; });
  const MaterialSpec& m = sc.material;
  if (m.model != MaterialModel::mass_spring && local && m.lambda > 10 * m.mu) {
    char buf[400];
    std::snprintf(
        buf, sizeof buf,
        "material.lambda is %.3g mu: where zones keep the volume, the volumetric term of each tet at "
        "this weight stiffens the body as a nearly incompressible UNH locks (Cook's membrane, 2-ring patches, "
        "h = 3: +0.8%% at mu, -4%% at 10 mu, -47%% at 5,000 mu; docs/results/infsup); lambda of about mu "
        "suffices",
        m.lambda / m.mu);
    sc.notes.emplace_back(buf);
  }
  sc.zones = std::move(c.zones);
  note_redundant_zones(sc);
}

InfSup zones_infsup(const Scene& sc) {
  std::vector<std::vector<int>> zones;
  for (const auto& z : sc.zones) zones.push_back(z.second);
  std::vector<std::pair<int, Eigen::Vector3d>> held;
  for (const Driver& d : sc.boundary)
    for (const Eigen::Vector3d& h : d.held)
      for (int n : d.nodes) held.emplace_back(n, h);
  return infsup_constant(sc.mesh, zones, sc.driven_nodes(), held);
}

}  // namespace isochor
