#include "isochor/scene/body_setup.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "isochor/base/error.hpp"
#include "isochor/core/csv.hpp"
#include "isochor/core/selection.hpp"
#include "isochor/scene/mesh_system.hpp"
#include "isochor/scene/skeleton_setup.hpp"

namespace isochor {

namespace {

// A region's tets: `zone` (a zone of [zones] by name) or `select` (a selection of tets).
std::vector<int> region_tets(const Section& m, const Scene& sc) {
  if (m.has("zone") == m.has("select"))
    m.fail("zone", "expected exactly one of zone (a zone's name) or select (a selection of tets)");
  if (m.has("select")) return select_tets(sc.mesh, Selection::parse(m.table("select")));
  const std::string zone = m.string("zone", "");
  std::string known;
  for (const auto& [name, tets] : sc.zones) {
    if (name == zone) return tets;
    known += (known.empty() ? "" : ", ") + name;
  }
  m.fail("zone", "no zone \"" + zone + "\" (the scene's zones: " + (known.empty() ? "none" : known) + ")");
  return {};
}

// Per tet of `tets`, from a CSV file with columns tet, ax, ay, az (rows of other tets ignored).
std::vector<Eigen::Vector3d> fibres_from_file(const Section& m, const Scene& sc, const std::vector<int>& tets) {
  const std::string path = sc.file.resolve_path(m.string("file", ""));
  std::map<int, Eigen::Vector3d> by_tet;
  try {
    const CsvTable t = read_csv_table(path, "a fibre file (CSV: tet,ax,ay,az)");
    const std::vector<double>*tet = t.column("tet"), *ax = t.column("ax"), *ay = t.column("ay"), *az = t.column("az");
    if (!tet || !ax || !ay || !az) throw Error(path + ":1: expected the columns tet, ax, ay, az");
    for (std::size_t r = 0; r < tet->size(); ++r) {
      const double e = (*tet)[r];
      const Eigen::Vector3d a((*ax)[r], (*ay)[r], (*az)[r]);
      if (e != std::floor(e) || e < 0 || e >= sc.mesh.num_tets())
        throw Error(path + ": row " + std::to_string(r + 2) + ": tet " + std::to_string(e) +
                    " is not a tet of the mesh (expected 0.." + std::to_string(sc.mesh.num_tets() - 1) + ")");
      if (!a.allFinite() || a.norm() < 1e-12)
        throw Error(path + ": row " + std::to_string(r + 2) + ": expected a finite, non-zero direction");
      by_tet[static_cast<int>(e)] = a.normalized();
    }
  } catch (const Error& e) {
    m.fail("file", e.what());
  }
  std::vector<Eigen::Vector3d> out;
  for (int e : tets) {
    const auto it = by_tet.find(e);
    if (it == by_tet.end()) m.fail("file", path + " has no fibre for tet " + std::to_string(e) + " of the muscle");
    out.push_back(it->second);
  }
  return out;
}

// Per tet of `tets`, from the mesh file's element data `field` (3 components).
std::vector<Eigen::Vector3d> fibres_from_mesh(const Section& m, const Scene& sc, const std::vector<int>& tets) {
  const std::string name = m.string("field");
  const auto it = sc.mesh.tet_fields.find(name);
  if (it == sc.mesh.tet_fields.end()) {
    std::string known;
    for (const auto& [other, f] : sc.mesh.tet_fields) known += (known.empty() ? "" : ", ") + other;
    m.fail("field", "the mesh has no element data \"" + name + "\" (" +
                        (known.empty() ? "it has none; fibres = \"mesh\" reads a .msh file's $ElementData"
                                       : "it has: " + known) +
                        ")");
  }
  const Mesh::TetField& f = it->second;
  if (f.components != 3)
    m.fail("field", "element data \"" + name + "\" has " + std::to_string(f.components) +
                        " components per tet, expected 3 (a direction)");
  std::vector<Eigen::Vector3d> out;
  for (int e : tets) {
    const Eigen::Vector3d a(f.values[3 * e], f.values[3 * e + 1], f.values[3 * e + 2]);
    if (!a.allFinite() || a.norm() < 1e-12)
      m.fail("field", "element data \"" + name + "\" gives tet " + std::to_string(e) + " of the muscle " +
                          (a.hasNaN() ? "no value" : "no finite, non-zero direction"));
    out.push_back(a.normalized());
  }
  return out;
}

std::vector<Eigen::Vector3d> parse_fibres(const Section& m, const Scene& sc, const std::vector<int>& tets) {
  const std::string kind = m.string("fibres");
  if (kind == "file") return fibres_from_file(m, sc, tets);
  if (kind == "mesh") return fibres_from_mesh(m, sc, tets);
  if (kind == "laplace") {
    for (const char* key : {"origin", "insertion"})
      if (!m.has(key)) m.fail(key, "missing, expected a selection of nodes (fibres = \"laplace\")");
    const std::vector<int> origin = select_nodes(sc.mesh, Selection::parse(m.table("origin")));
    const std::vector<int> insertion = select_nodes(sc.mesh, Selection::parse(m.table("insertion")));
    try {
      return laplace_fibres(sc.mesh, tets, origin, insertion);
    } catch (const Error& e) {
      m.fail("origin", e.what());
    }
  }
  const std::optional<Eigen::Vector3d> a = m.vec3_opt("direction");
  if (!a || a->norm() < 1e-12)
    m.fail("direction", "expected a non-zero fibre direction [x, y, z] (fibres = \"constant\")");
  return std::vector<Eigen::Vector3d>(tets.size(), a->normalized());
}

// activation_bvh: the channel's keys against time (one per frame, the file's units) and the
// table of its value.
void parse_bvh_activation(const Section& k, const Scene& sc, ActivationCurve& a) {
  for (const char* key : {"file", "joint", "channel"})
    if (!k.has(key)) k.fail(key, "missing, activation_bvh needs file, joint and channel");
  const std::string path = sc.file.resolve_path(k.string("file", ""));
  Bvh bvh;
  try {
    bvh = read_bvh(path);
  } catch (const Error& e) {
    k.fail("file", e.what());
  }
  const std::string joint = k.string("joint", "");
  const int j = bvh.find(joint);
  if (j < 0) k.fail("joint", "\"" + joint + "\" is not a joint of " + path);
  const BvhJoint& J = bvh.joints[j];
  const std::string channel = k.string("channel", "");
  std::string has;
  for (std::size_t c = 0; c < J.channels.size(); ++c) {
    if (channel == bvh_channel_name(J.channels[c])) {
      a.channel = bvh_keyframes(bvh, J, {static_cast<int>(c)}, 1.0);
      return;
    }
    has += std::string(has.empty() ? "" : ", ") + bvh_channel_name(J.channels[c]);
  }
  k.fail("channel", "joint \"" + joint + "\" of " + path + " has no channel \"" + channel +
                        "\" (its channels: " + (has.empty() ? "none" : has) + ")");
}

// The bone and joint angle that key activation_joint.
void parse_joint_activation(const Section& k, const Scene& sc, ActivationCurve& a) {
  const std::string bone = k.string("bone", "");
  if (!sc.skeleton) k.fail("bone", "the scene has no [skeleton]");
  const auto& bones = sc.skeleton->bones();
  for (std::size_t b = 0; b < bones.size(); ++b)
    if (bones[b].name == bone) a.bone = static_cast<int>(b);
  if (a.bone < 0) k.fail("bone", "no bone \"" + bone + "\" in [skeleton]");
  const int angles = bones[a.bone].angles;
  if (angles == 0) k.fail("bone", "bone \"" + bone + "\" has a weld joint: it has no angle");
  a.axis = static_cast<int>(k.integer("axis"));
  if (a.axis >= angles)
    k.fail("axis", "expected an integer in [0, " + std::to_string(angles - 1) + "] (the joint's angles), got " +
                       std::to_string(a.axis));
}

ActivationCurve parse_activation(const Section& m, const Scene& sc) {
  ActivationCurve a;
  static const char* sources[] = {"activation_keys", "activation_joint", "activation_bvh"};
  static const char* knots[] = {"times", "angles", "channel_values"};
  int given = 0, which = 0;
  for (int s = 0; s < 3; ++s)
    if (m.has(sources[s])) ++given, which = s;
  if (given > 1) m.fail(sources[which], "expected one of activation_keys, activation_joint or activation_bvh");
  a.value = m.number("activation");
  if (given && m.has("activation"))
    m.fail("activation", "not with activation_keys, activation_joint or activation_bvh");
  if (!given) return a;
  const Section k = m.table(sources[which]);
  a.curve = parse_keyframes(k, "values", 1, 1.0, "one activation", knots[which], which == 1 ? M_PI / 180.0 : 1.0);
  for (const Eigen::Vector3d& v : a.curve.values)
    if (v.x() < 0 || v.x() > 1) k.fail("values", "expected activations in [0, 1]");
  a.source = ActivationCurve::Source::time;
  if (which == 1) {
    a.source = ActivationCurve::Source::joint;
    parse_joint_activation(k, sc, a);
  } else if (which == 2) {
    a.source = ActivationCurve::Source::channel;
    parse_bvh_activation(k, sc, a);
  }
  return a;
}

}  // namespace

void parse_material_regions(const Section& material, Scene& sc) {
  for (const Section& r : material.tables("region")) {
    if (sc.material.model == MaterialModel::mass_spring || sc.integrator.kind == IntegratorKind::xpbd)
      r.fail("zone",
             "material regions need a tet material on IDA, statics or backward Euler (not mass_spring or xpbd)");
    MaterialSpec::Region region;
    region.tets = region_tets(r, sc);
    std::tie(region.mu, region.lambda) = parse_lame(r, sc.material.mu, sc.material.lambda);
    if (!std::isfinite(region.lambda)) r.fail("nu", "expected nu < 0.5 (nu = 0.5 is for XPBD's incompressible limit)");
    region.density = r.number("density", sc.material.density);
    sc.material.regions.push_back(std::move(region));
  }
}

TetMaterials scene_tet_materials(const Scene& sc) {
  TetMaterials t;
  if (sc.material.regions.empty()) return t;
  t.materials.push_back(make_material(sc.material));
  t.material_of.assign(sc.mesh.num_tets(), 0);
  t.density.assign(sc.mesh.num_tets(), sc.material.density);
  for (const MaterialSpec::Region& r : sc.material.regions) {
    MaterialSpec m = sc.material;
    m.mu = r.mu;
    m.lambda = r.lambda;
    t.materials.push_back(make_material(m));
    for (int e : r.tets) {
      t.material_of[e] = static_cast<int>(t.materials.size()) - 1;
      t.density[e] = r.density;
    }
  }
  return t;
}

void parse_muscles(const Section& root, Scene& sc) {
  sc.activation_scale = root.table("muscles").number("activation_scale");
  std::vector<int> owner(sc.mesh.num_tets(), -1);
  for (const Section& m : root.tables("muscle")) {
    Scene::MuscleSpec spec;
    spec.name = m.string("name", "");
    if (spec.name.empty() || spec.name.find_first_of("/.,") != std::string::npos)
      m.fail("name", "expected a muscle name without '/', '.' or ','");
    for (const auto& other : sc.muscles)
      if (other.name == spec.name) m.fail("name", "muscle \"" + spec.name + "\" is defined twice");
    if (sc.material.model == MaterialModel::mass_spring || sc.integrator.kind == IntegratorKind::xpbd)
      m.fail("name", "muscles need a tet material on IDA, statics or backward Euler (not mass_spring or xpbd)");
    spec.tets = region_tets(m, sc);
    for (int e : spec.tets) {
      if (owner[e] >= 0)
        m.fail("zone", "tet " + std::to_string(e) + " is also in muscle \"" + sc.muscles[owner[e]].name +
                           "\" (a tet belongs to one muscle)");
      owner[e] = static_cast<int>(sc.muscles.size());
    }
    spec.fibres = parse_fibres(m, sc, spec.tets);
    spec.law.sigma_max = m.number("sigma_max", spec.law.sigma_max);
    spec.law.optimal_stretch = m.number("optimal_stretch");
    spec.law.k1 = m.number("passive_k1");
    spec.law.k2 = m.number("passive_k2");
    spec.activation = parse_activation(m, sc);
    sc.muscles.push_back(std::move(spec));
  }
}

FibreField scene_fibre_field(const Scene& sc) {
  FibreField f;
  if (sc.muscles.empty()) return f;
  f.muscle_of.assign(sc.mesh.num_tets(), -1);
  f.direction.assign(sc.mesh.num_tets(), Vec3::UnitX());
  for (std::size_t m = 0; m < sc.muscles.size(); ++m) {
    f.muscles.push_back(sc.muscles[m].law);
    for (std::size_t k = 0; k < sc.muscles[m].tets.size(); ++k) {
      f.muscle_of[sc.muscles[m].tets[k]] = static_cast<int>(m);
      f.direction[sc.muscles[m].tets[k]] = sc.muscles[m].fibres[k];
    }
  }
  return f;
}

std::vector<double> Scene::activations(double t) const {
  std::vector<double> a;
  for (const MuscleSpec& m : muscles) a.push_back(m.activation.at(t, skeleton.get(), activation_scale));
  return a;
}

}  // namespace isochor
