#include "isochor/scene/scene.hpp"
#include "isochor/scene/body_setup.hpp"
#include "isochor/scene/character_setup.hpp"
#include "isochor/scene/skeleton_setup.hpp"
#include "isochor/scene/zones_setup.hpp"
#include "isochor/core/paint.hpp"
#include "isochor/scene/integrator_registry.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>

#include "isochor/models/constraints.hpp"
#include "isochor/base/error.hpp"
#include "isochor/core/csv.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/core/selection.hpp"

namespace isochor {

std::pair<double, double> lame_from_young(double E, double nu) {
  return {E / (2.0 * (1.0 + nu)), E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))};
}

long FramesSpec::num_frames() const {
  if (count > 0) return count;
  return std::lround(std::floor(duration * rate + 1e-9)) + 1;
}

std::vector<double> FramesSpec::times() const {
  std::vector<double> t;
  if (count > 0) {  // statics: pseudo-time 0 .. 1 over the load increments
    if (count == 1) return {1.0};
    for (int k = 0; k < count; ++k) t.push_back(static_cast<double>(k) / (count - 1));
    return t;
  }
  const long n = std::lround(std::floor(duration * rate + 1e-9));
  for (long k = 0; k <= n; ++k) t.push_back(static_cast<double>(k) / rate);
  return t;
}

double Scene::gravity_scale(double t) const { return gravity_ramp > 0 ? std::clamp(t / gravity_ramp, 0.0, 1.0) : 1.0; }

std::vector<int> Scene::driven_nodes() const {
  std::vector<int> driven;
  for (const Driver& d : boundary)
    if (d.held.empty()) driven.insert(driven.end(), d.nodes.begin(), d.nodes.end());
  if (skeleton) {
    const std::vector<int> bound = skeleton->bound_nodes();
    driven.insert(driven.end(), bound.begin(), bound.end());
  }
  return driven;
}

void Scene::drive(double t, Points& x, Eigen::VectorXd* xdot) const {
  for (const Driver& d : boundary)
    if (d.held.empty()) d.apply(mesh.rest_positions(), t, x, xdot);
  if (skeleton) skeleton->apply(mesh.rest_positions(), t, x, xdot);
}

std::vector<double> Scene::breakpoints() const {
  std::vector<double> t;
  for (const Driver& d : boundary) d.breakpoints(t);
  if (skeleton)
    for (const BoneSpec& b : skeleton->bones()) b.breakpoints(t);
  for (const Collider& c : colliders) {
    c.motion.breakpoints(t);
    c.resize.breakpoints(t);
  }
  for (const MuscleSpec& m : muscles)
    if (m.activation.source == ActivationCurve::Source::time) m.activation.curve.breakpoints(t);
  for (const MuscleSpec& m : muscles)
    if (m.activation.source == ActivationCurve::Source::channel) m.activation.channel.breakpoints(t);
  if (gravity_ramp > 0) t.push_back(gravity_ramp);
  if (zone_restore_time > 0 && keep_zones && !zones.empty()) t.push_back(frames.times().front() + zone_restore_time);
  for (const NodeLoad& l : loads) l.history.breakpoints(t);
  for (const PressureLoad& l : pressure_loads) l.history.breakpoints(t);
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end()), t.end());
  return t;
}

Driver parse_keyframes(const Section& b, const std::string& key, int per_time, double scale, const std::string& what,
                       const std::string& knots, double knot_scale) {
  Driver d;
  const std::string interp = b.string("interpolation");
  d.kind = interp == "linear" ? Driver::Kind::keyframes_linear : Driver::Kind::keyframes_cubic;
  d.times = b.numbers(knots);
  const std::vector<double> flat = b.numbers(key);
  const std::string unit = knots == "times" ? " (s)" : "";
  if (d.times.size() < 2) b.fail(knots, "expected at least 2 keyframe " + knots + unit);
  for (std::size_t i = 1; i < d.times.size(); ++i)
    if (d.times[i] <= d.times[i - 1]) b.fail(knots, "expected increasing " + knots);
  for (double& t : d.times) t *= knot_scale;
  const std::size_t n = static_cast<std::size_t>(per_time) * d.times.size();
  if (flat.size() != n)
    b.fail(key, "expected " + what + " per keyframe time, " + std::to_string(n) + " numbers in all, got " +
                    std::to_string(flat.size()));
  for (std::size_t i = 0; i < d.times.size(); ++i) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int k = 0; k < per_time; ++k) v[k] = scale * flat[per_time * i + k];
    d.values.push_back(v);
  }
  return d;
}

namespace {

// A string key with a fixed set of choices, as an enum.
template <class E>
E parse_choice(const Section& s, std::string_view key, E fallback,
               const std::vector<std::pair<std::string, E>>& table) {
  std::vector<std::string> names;
  std::string name;
  for (const auto& [n, e] : table) {
    names.push_back(n);
    if (e == fallback && name.empty()) name = n;
  }
  name = s.string(key, name);
  for (const auto& [n, e] : table)
    if (n == name) return e;
  throw std::logic_error(s.path() + "." + std::string(key) + ": \"" + name + "\" is declared but not parsed");
}

const std::vector<std::pair<std::string, MaterialModel>> kModels = {{"cnh", MaterialModel::cnh},
                                                                    {"unh", MaterialModel::unh},
                                                                    {"snh", MaterialModel::snh},
                                                                    {"snh_simple", MaterialModel::snh_simple},
                                                                    {"mass_spring", MaterialModel::mass_spring}};

template <class E>
const char* name_of(const std::vector<std::pair<std::string, E>>& table, E e) {
  for (const auto& [n, v] : table)
    if (v == e) return n.c_str();
  return "?";
}

}  // namespace

std::pair<double, double> parse_lame(const Section& s, double mu, double lambda) {
  const bool lame = s.has("mu") || s.has("lambda"), young = s.has("E") || s.has("nu");
  if (lame && young) s.fail(s.has("E") ? "E" : "nu", "give either mu and lambda or E and nu, not both");
  if (!young) return {s.number("mu", mu), s.number("lambda", lambda)};
  const double E = s.number("E", 1e5);
  const double nu = s.number("nu", 0.45);
  if (nu == 0.5) return {lame_from_young(E, nu).first, std::numeric_limits<double>::infinity()};  // XPBD only
  return lame_from_young(E, nu);
}

namespace {

MaterialSpec parse_material(const Section& s) {
  MaterialSpec m;
  m.model = parse_choice(s, "model", m.model, kModels);
  m.density = s.number("density", m.density);
  std::tie(m.mu, m.lambda) = parse_lame(s, 1e4, 9e4);
  m.beta = s.number("beta", m.beta);
  m.epsilon = s.number("epsilon", m.epsilon);
  m.epidermis_lambda = s.number("epidermis_lambda");
  m.epidermis_gamma = s.number("epidermis_gamma");
  // The mass-spring keys are read for every model, so one scene can switch models by --set.
  m.spring_stiffness = s.number("spring_stiffness", m.spring_stiffness);
  m.spring_damping = s.number("spring_damping", m.spring_damping);
  m.volume_constraint = s.boolean("volume_constraint", true);
  return m;
}

// A motion in time: `kind` ("fixed", "ramp", "keyframes", "sinusoid", "rotation") and its keys.
Driver parse_motion(const Section& b) {
  Driver d;
  const std::string kind = b.string("kind", "fixed");
  if (kind == "ramp") {
    d.kind = Driver::Kind::ramp;
    if (!b.has("displacement")) b.fail("displacement", "missing, a ramp needs its end displacement [x, y, z] (m)");
    d.vector = b.vec3("displacement", {});
    d.t0 = b.number("t0");
    d.t1 = b.number("t1");
    if (d.t1 <= d.t0) b.fail("t1", "expected t1 > t0");
  } else if (kind == "sinusoid") {
    d.kind = Driver::Kind::sinusoid;
    if (!b.has("amplitude")) b.fail("amplitude", "missing, a sinusoid needs its amplitude [x, y, z] (m)");
    d.vector = b.vec3("amplitude", {});
    d.frequency = b.number("frequency");
    d.phase = b.number("phase");
  } else if (kind == "rotation") {
    d = parse_keyframes(b, "angles", 1, M_PI / 180.0, "one angle (degrees)");
    d.rotation = true;
    d.center = b.vec3("center");
    d.axis = b.vec3("axis", Eigen::Vector3d::UnitZ());
    if (d.axis.norm() == 0) b.fail("axis", "expected a non-zero vector");
    d.axis.normalize();
  } else if (kind == "keyframes") {
    d = parse_keyframes(b, "values", 3, 1.0, "3 numbers (a displacement)");
  }
  return d;
}

Driver parse_boundary(const Section& b, const Mesh& mesh) {
  const Section sel = b.table("select");
  if (!sel.exists()) b.fail("select", "missing, expected the nodes to drive, e.g. { kind = \"set\", name = \"zmin\" }");
  const std::vector<int> nodes = select_nodes(mesh, Selection::parse(sel));
  Driver d = parse_motion(b);
  d.nodes = nodes;
  // Which components the driver holds: all (default), some axes, or the normal of a plane.
  if (b.has("components") && b.has("normal")) b.fail("normal", "give either components or normal, not both");
  if (b.has("components")) {
    const std::vector<std::string> c = b.strings("components");
    if (c.empty()) b.fail("components", "expected at least one of \"x\", \"y\", \"z\"");
    std::set<std::string> seen;
    for (const std::string& name : c) {
      if (name != "x" && name != "y" && name != "z")
        b.fail("components", "unknown component \"" + name + "\" (expected \"x\", \"y\" or \"z\")");
      if (!seen.insert(name).second) b.fail("components", "component \"" + name + "\" given twice");
    }
    if (seen.size() < 3)
      for (const std::string& name : c) d.held.push_back(Eigen::Vector3d::Unit(name[0] - 'x'));
  } else if (b.has("normal")) {
    const Eigen::Vector3d n = b.vec3("normal", {});
    if (n.norm() == 0) b.fail("normal", "expected a non-zero vector");
    d.held.push_back(n.normalized());
  }
  if (!d.held.empty() && d.rotation)
    b.fail(b.has("normal") ? "normal" : "components",
           "a rotation drives all three components (expected no components or normal with kind = \"rotation\")");
  return d;
}

// initial.flatten: the XPBD paper's scrambled start. Every node is moved into the plane through the
// mesh's centre normal to the axis, at a uniformly random point of the mesh's bounding box in the
// other two axes (std::mt19937_64 seeded by initial.seed: the same start on every run). With
// initial.spread = s < 1, a node goes to (1 - s) of the way from that random point to its rest
// position projected into the plane (s = 0: the body squashed flat; the random points drawn are
// the same for every s).
void parse_flatten(const Section& in, Scene& sc) {
  const std::string axis = in.string("flatten");
  const auto seed = in.integer("seed");
  const double spread = in.number("spread");
  if (axis == "none") return;  // a seed and spread are kept for a --set initial.flatten variant
  const int a = axis[0] - 'x';
  const Points& X = sc.mesh.rest_positions();
  const Eigen::Vector3d lo = X.rowwise().minCoeff(), hi = X.rowwise().maxCoeff();
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  sc.initial_positions.resize(3, X.cols());
  for (Eigen::Index n = 0; n < X.cols(); ++n)
    for (int d = 0; d < 3; ++d) {
      const double u = d == a ? 0.5 : unit(rng);
      const double random = lo[d] + u * (hi[d] - lo[d]);
      sc.initial_positions(d, n) = d == a ? random : spread * random + (1 - spread) * X(d, n);
    }
}

// initial.from = "RUN.h5": every node's position and velocity at frame initial.frame (from the
// end when negative; -1, the last, by default) of another run of the same mesh (its node count and
// rest positions): a dynamic run from a static equilibrium, or on from another run's state with
// another method or scene. Driven nodes follow their drivers from t = 0 as always.
void parse_start_from(const Section& in, Scene& sc) {
  const std::string from = in.string("from", "");
  const long frame = in.integer("frame");
  if (from.empty()) {
    if (in.has("frame")) in.fail("frame", "picks a frame of initial.from (expected initial.from = \"RUN.h5\")");
    return;
  }
  if (sc.initial_positions.cols())
    in.fail("from", "a run's state and initial.flatten both set the start (expected one)");
  if (in.has("velocity"))
    in.fail("velocity", "the run's velocities start the nodes (expected initial.from or initial.velocity)");
  const std::string path = sc.file.resolve_path(from);
  // The run file's own errors (missing, not a run, no velocities) named with the key.
  auto read = [&](auto what) {
    try {
      return what();
    } catch (const Error& e) {
      in.fail("from", e.what());
    }
  };
  const auto run = read([&] { return std::make_unique<RunFile>(path); });
  const int frames = read([&] { return run->num_frames(); });
  const long k = frame < 0 ? frames + frame : frame;
  if (k < 0 || k >= frames)
    in.fail("frame", std::to_string(frame) + " is not a frame of " + from + " (expected -" + std::to_string(frames) +
                         " .. " + std::to_string(frames - 1) + ")");
  const Points& X = sc.mesh.rest_positions();
  const Points R = read([&] { return run->rest_positions(); });
  const double size = (X.rowwise().maxCoeff() - X.rowwise().minCoeff()).norm();
  if (R.cols() != X.cols() || (R - X).cwiseAbs().maxCoeff() > 1e-9 * size)
    in.fail("from", from + " is a run of another mesh (" + std::to_string(R.cols()) + " nodes against the scene's " +
                        std::to_string(X.cols()) + ", or other rest positions; expected a run of this scene's mesh)");
  sc.initial_positions = read([&] { return run->positions(static_cast<int>(k)); });
  sc.initial_velocities = read([&] { return run->velocities(static_cast<int>(k)); });
}

// initial.displacement = "FILE.csv": columns node, ux, uy, uz; each listed node starts displaced
// from its rest position by (ux, uy, uz) m, the others at rest (velocities initial.velocity).
void parse_start_displacement(const Section& in, Scene& sc) {
  if (!in.has("displacement")) return;
  if (sc.initial_positions.cols())
    in.fail("displacement", "initial.flatten or initial.from also sets the start (expected one of the three)");
  const std::string path = sc.file.resolve_path(in.string("displacement", ""));
  const int nodes = sc.mesh.num_nodes();
  Points x = sc.mesh.rest_positions();
  std::vector<char> seen(static_cast<std::size_t>(nodes), 0);
  try {
    const CsvTable t = read_csv_table(path, "a displacement file (CSV: node,ux,uy,uz)");
    const std::vector<double>*node = t.column("node"), *ux = t.column("ux"), *uy = t.column("uy"), *uz = t.column("uz");
    if (!node || !ux || !uy || !uz) throw Error(path + ":1: expected the columns node, ux, uy, uz");
    const double size = (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
    for (std::size_t r = 0; r < node->size(); ++r) {
      const double v = (*node)[r];
      const Eigen::Vector3d u((*ux)[r], (*uy)[r], (*uz)[r]);
      const std::string row = path + ":" + std::to_string(r + 2) + ": ";
      if (v != std::floor(v) || v < 0 || v >= nodes)
        throw Error(row + "node " + std::to_string(v) + " is not a node of the mesh (expected 0.." +
                    std::to_string(nodes - 1) + ")");
      const auto n = static_cast<std::size_t>(v);
      if (seen[n]) throw Error(row + "node " + std::to_string(n) + " is listed twice");
      if (!u.allFinite() || u.norm() > 1e3 * size)
        throw Error(row + "expected a finite displacement within 1000 times the mesh's size");
      seen[n] = 1;
      x.col(static_cast<Eigen::Index>(n)) += u;
    }
  } catch (const Error& e) {
    in.fail("displacement", e.what());
  }
  sc.initial_positions = x;
}

// IDA starts from a consistent state: a start whose zones are not at their rest volumes (every
// zone flat after initial.flatten; a run of another model after initial.from) cannot meet them at
// t = 0 (it would fail there with IDA_CONV_FAIL and no hint) without zones.restore_time.
void check_start_volumes(const Section& initial, const Scene& sc) {
  const char* restore = " (expected zones.restore_time > 0: the volumes restored over that time)";
  if (!initial.has("from") && !initial.has("displacement"))
    initial.fail(
        "flatten",
        std::string("starts every zone at volume 0, which IDA cannot hold to its rest volume at t = 0") + restore);
  for (const auto& [name, tets] : sc.zones) {
    std::vector<Tet> zone;
    for (int t : tets) zone.push_back(sc.mesh.tets()[static_cast<std::size_t>(t)]);
    const double rest = tets_volume(sc.mesh.rest_positions(), zone), start = tets_volume(sc.initial_positions, zone);
    if (std::abs(start / rest - 1) > 1e-8) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "the zone %s starts %.3g%% off its rest volume, which IDA cannot hold at t = 0",
                    name.c_str(), 100 * (start / rest - 1));
      initial.fail(initial.has("from") ? "from" : "displacement", buf + std::string(restore));
    }
  }
}

// [[load]]: a point load on a node set (the force split among the nodes, or on each), a
// traction on the surface triangles whose corners are all selected (rest area, a third to each
// corner: the consistent load of linear triangles), or a pressure on those triangles (a follower
// load, forces.hpp).
void parse_load(const Section& l, const Mesh& mesh, Scene& sc) {
  const Section sel = l.table("select");
  if (!sel.exists()) l.fail("select", "missing, expected the nodes to load, e.g. { kind = \"set\", name = \"xmax\" }");
  const std::vector<int> nodes = select_nodes(mesh, Selection::parse(sel));
  const std::string kind = l.string("kind", "point");
  LoadHistory history;
  history.ramp = l.number("ramp");
  if (l.has("times") || l.has("factors")) {
    if (l.has("ramp")) l.fail("ramp", "give either ramp or times and factors, not both");
    history.times = l.numbers("times");
    history.factors = l.numbers("factors");
    if (history.times.size() < 2) l.fail("times", "expected at least 2 increasing times (s)");
    if (history.factors.size() != history.times.size())
      l.fail("factors", "expected one factor per time (" + std::to_string(history.times.size()) + "), got " +
                            std::to_string(history.factors.size()));
    for (std::size_t i = 1; i < history.times.size(); ++i)
      if (!(history.times[i] > history.times[i - 1])) l.fail("times", "expected increasing times");
  }
  if (kind == "point") {
    if (!l.has("force")) l.fail("force", "missing, a point load needs its force [x, y, z] (N)");
    const Vec3 f = l.vec3("force", {});
    const bool split = l.boolean("split", true);
    sc.loads.push_back(
        {nodes, std::vector<Vec3>(nodes.size(), split ? Vec3(f / static_cast<double>(nodes.size())) : f), history});
    return;
  }
  std::vector<char> in(mesh.num_nodes(), 0);
  for (int v : nodes) in[v] = 1;
  std::vector<Tri> faces;
  for (const Tri& t : mesh.surface())
    if (in[t[0]] && in[t[1]] && in[t[2]]) faces.push_back(t);
  if (faces.empty())
    l.fail("select", "selects no surface triangle (expected the corners of at least one boundary face)");
  if (kind == "pressure") {
    if (!l.has("pressure")) l.fail("pressure", "missing, a pressure load needs its pressure (Pa)");
    sc.pressure_loads.push_back({faces, l.number("pressure", 0.0), history});
    return;
  }
  if (!l.has("traction")) l.fail("traction", "missing, a traction needs its force per area [x, y, z] (N/m^2)");
  const Vec3 tr = l.vec3("traction", {});
  std::map<int, Vec3> per_node;
  const Points& X = mesh.rest_positions();
  for (const Tri& t : faces) {
    const double area = 0.5 * (X.col(t[1]) - X.col(t[0])).cross(X.col(t[2]) - X.col(t[0])).norm();
    for (int v : t) per_node.try_emplace(v, Vec3::Zero()).first->second += tr * area / 3.0;
  }
  NodeLoad load;
  load.history = history;
  for (const auto& [v, f] : per_node) {
    load.nodes.push_back(v);
    load.force.push_back(f);
  }
  sc.loads.push_back(std::move(load));
}

}  // namespace

namespace {

// A contact law: `defaults` ([contact]'s, or built-in ones) for keys the table does not give.
ContactLaw parse_contact_law(const Section& c, const ContactLaw& defaults) {
  ContactLaw L;
  L.stiffness = c.number("stiffness", defaults.stiffness);
  L.thickness = c.number("thickness", defaults.thickness);
  L.per_area = c.string("law", defaults.per_area ? "area" : "node") == "area";
  L.damping = c.number("damping", defaults.damping);
  L.friction = c.number("friction", defaults.friction);
  L.slip_speed = c.number("slip_speed", defaults.slip_speed);
  return L;
}

Eigen::Vector3d nonzero_vec3(const Section& s, std::string_view key, const Eigen::Vector3d& fallback) {
  const Eigen::Vector3d v = s.vec3(key, fallback);
  if (v.norm() == 0) s.fail(key, "expected a non-zero vector");
  return v.normalized();
}

double required_positive(const Section& s, std::string_view key, const std::string& what) {
  if (!s.has(key)) s.fail(key, "missing, " + what);
  return s.number(key, 0.0);
}

// A [[collider]] with shape = "mesh": its closed surface (`file`, scaled by `scale`) and the smoothed
// signed distance sampled on cells of `cell` (default: a 64th of the surface's longest side).
std::shared_ptr<const MeshSdf> parse_mesh_shape(const Section& c, const SceneFile& file, double thickness) {
  if (!c.has("file")) c.fail("file", "missing, a mesh collider needs a closed triangle surface (.obj or .stl)");
  const std::string path = file.resolve_path(c.string("file", ""));
  const double scale = c.number("scale");
  Points x;
  std::vector<Tri> tris;
  try {
    read_surface(path, x, tris);
  } catch (const Error& e) {
    c.fail("file", e.what());
  }
  x *= scale;
  const double longest = x.cols() ? (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).maxCoeff() : 0.0;
  if (x.cols() && !(longest >= 1e-6 && longest <= 1e6)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "%g makes the surface %g m across (expected 1e-06 to 1e+06 m: sizes are in metres)",
                  scale, longest);
    c.fail("scale", buf);
  }
  const double cell = c.number("cell", longest / 64);
  try {
    // The samples reach past the contact thickness by four cells (the spline's support and more).
    return std::make_shared<const MeshSdf>(x, tris, cell, thickness + 4 * cell, path);
  } catch (const Error& e) {
    c.fail(c.has("cell") ? "cell" : "file", e.what());
  }
  return nullptr;
}

// A collider's motion: carried by a bone, moved by a driver's motion, or static.
void parse_collider_motion(const Section& c, const Scene& sc, Collider& C) {
  const Section motion = c.table("motion");
  if (c.has("bone")) {
    if (motion.exists()) c.fail("motion", "a collider follows a bone or a motion, not both");
    const std::string bone = c.string("bone", "");
    if (!sc.skeleton) c.fail("bone", "the scene has no [skeleton] (expected a bone name from [[skeleton.bone]])");
    const auto& bones = sc.skeleton->bones();
    for (std::size_t b = 0; b < bones.size(); ++b)
      if (bones[b].name == bone) C.bone = static_cast<int>(b);
    if (C.bone < 0) c.fail("bone", "no bone named \"" + bone + "\" in [skeleton]");
  } else if (motion.exists()) {
    C.motion = parse_motion(motion);
  }
}

// A round collider's radius factor in time (resize: keyframes of positive factors).
void parse_collider_resize(const Section& c, Collider& C) {
  using K = ColliderShape::Kind;
  const ColliderShape& S = C.shape;
  const Section resize = c.table("resize");
  if (!resize.exists()) return;
  if (S.kind != K::sphere && S.kind != K::capsule && S.kind != K::cylinder)
    c.fail("resize", "only a sphere's, capsule's or cylinder's radius can change");
  if (C.law.damping > 0 || C.law.friction > 0)
    c.fail("resize",
           "a collider whose radius changes has no damping or friction (expected damping = 0 and friction = 0)");
  C.resize = parse_keyframes(resize, "factors", 1, 1.0, "one factor on the radius");
  for (const Eigen::Vector3d& f : C.resize.values)
    if (!(f.x() > 0)) resize.fail("factors", "expected positive factors on the radius");
  double smallest_factor = 1.0;
  for (const Eigen::Vector3d& f : C.resize.values) smallest_factor = std::min(smallest_factor, f.x());
  if (S.kind == K::cylinder && S.wall == 0 && S.rounding > S.radius * smallest_factor)
    resize.fail("factors", "the radius would shrink below the rounding (" + std::to_string(S.rounding) + " m)");
}

// One [[collider]]: its shape, pose, law and motion (docs/scenes.md).
Collider parse_collider(const Section& c, const Scene& sc, const ContactLaw& defaults) {
  Collider C;
  C.name = c.path();
  using K = ColliderShape::Kind;
  if (!c.has("shape"))
    c.fail("shape", "missing, expected one of \"plane\", \"sphere\", \"capsule\", \"box\", \"cylinder\", \"mesh\"");
  C.shape.kind = parse_choice<K>(c, "shape", K::plane,
                                 {{"plane", K::plane},
                                  {"sphere", K::sphere},
                                  {"capsule", K::capsule},
                                  {"box", K::box},
                                  {"cylinder", K::cylinder},
                                  {"mesh", K::mesh}});
  ColliderShape& S = C.shape;
  C.law = parse_contact_law(c, defaults);
  C.center = c.vec3("center");
  const Eigen::Vector3d axis = nonzero_vec3(c, "axis", Eigen::Vector3d::UnitZ());
  const double angle = c.number("angle") * M_PI / 180.0;
  // A mesh keeps its file's frame, turned by `angle` about `axis`; the other shapes' axis is `axis`.
  C.rotation = S.kind == K::mesh ? Mat3(Eigen::AngleAxisd(angle, axis)) : frame_with_axis(axis, angle);
  double smallest = 0;  // the smallest half dimension (bounds the rounding)
  switch (S.kind) {
    case K::plane:
      break;
    case K::sphere:
      S.radius = required_positive(c, "radius", "a sphere needs its radius (m)");
      break;
    case K::capsule:
      S.radius = required_positive(c, "radius", "a capsule needs its radius (m)");
      S.half_length = 0.5 * required_positive(c, "length", "a capsule needs the length of its axis segment (m)");
      break;
    case K::box: {
      if (!c.has("size")) c.fail("size", "missing, a box needs its edge lengths [x, y, z] (m)");
      const Eigen::Vector3d size = c.vec3("size", {});
      if (size.minCoeff() <= 0 || size.maxCoeff() > 1e6)
        c.fail("size", "expected three positive edge lengths of at most 1e+06 m");
      S.half_extents = 0.5 * size;
      smallest = S.half_extents.minCoeff();
      break;
    }
    case K::cylinder:
      S.radius = required_positive(c, "radius", "a cylinder needs its radius (m; hollow: the hole's)");
      S.half_length = 0.5 * required_positive(c, "length", "a cylinder needs its height (m)");
      S.wall = c.number("wall");
      smallest = std::min(S.half_length, S.wall > 0 ? 0.5 * S.wall : S.radius);
      break;
    case K::mesh:
      S.mesh = parse_mesh_shape(c, sc.file, C.law.thickness);
      break;
  }
  if (S.kind == K::box || S.kind == K::cylinder) {
    S.rounding = c.number("rounding", 0.1 * smallest);
    if (S.rounding > smallest)
      c.fail("rounding", "expected at most " + std::to_string(smallest) + " m (half the shape's smallest dimension)");
  }
  parse_collider_motion(c, sc, C);
  parse_collider_resize(c, C);
  return C;
}

// contact.ground, [[contact.plane]] and [[collider]] into sc.colliders.
void parse_colliders(const Section& root, Scene& sc) {
  const Section contact = root.table("contact");
  const ContactLaw defaults = parse_contact_law(contact, ContactLaw{});
  if (contact.boolean("ground", false)) {
    sc.colliders.push_back(Collider::plane(contact.vec3("point", Eigen::Vector3d::Zero()),
                                           nonzero_vec3(contact, "normal", Eigen::Vector3d::UnitZ()), defaults));
    sc.colliders.back().name = "contact.ground";
  } else {
    contact.vec3("point", Eigen::Vector3d::Zero());  // read (and checked) for a --set contact.ground variant
    nonzero_vec3(contact, "normal", Eigen::Vector3d::UnitZ());
  }
  for (const Section& p : contact.tables("plane")) {
    if (!p.has("point") || !p.has("normal"))
      p.fail(p.has("point") ? "normal" : "point", "missing, a contact plane needs a point and a normal");
    Collider C = Collider::plane(p.vec3("point", {}), nonzero_vec3(p, "normal", {}), parse_contact_law(p, defaults));
    C.name = p.path();
    const Eigen::Vector3d u = p.vec3("displacement", Eigen::Vector3d::Zero());
    const double t0 = p.number("t0"), t1 = p.number("t1");
    if (t1 <= t0) p.fail("t1", "expected t1 > t0");
    if (u.squaredNorm() > 0) {
      C.motion.kind = Driver::Kind::ramp;
      C.motion.vector = u;
      C.motion.t0 = t0;
      C.motion.t1 = t1;
    }
    sc.colliders.push_back(C);
  }
  for (const Section& c : root.tables("collider")) sc.colliders.push_back(parse_collider(c, sc, defaults));
  const Section self = contact.table("self");
  if (self.exists()) {
    sc.self_contact.enabled = self.boolean("enabled", true);
    ContactLaw plain = defaults;  // the ground's damping and friction are not inherited
    plain.damping = plain.friction = 0;
    sc.self_contact.law = parse_contact_law(self, plain);
    if (sc.self_contact.law.friction > 0)
      self.fail("friction", "contact between body parts has no friction (expected 0)");
    // The default neighbourhood: three mean surface edges.
    const Points& X = sc.mesh.rest_positions();
    double edges = 0;
    for (const Tri& t : sc.mesh.surface())
      for (int e = 0; e < 3; ++e) edges += (X.col(t[e]) - X.col(t[(e + 1) % 3])).norm();
    const double mean = sc.mesh.surface().empty() ? 0.0 : edges / (3.0 * static_cast<double>(sc.mesh.surface().size()));
    sc.self_contact.exclude = self.number("exclude", 3 * mean);
    sc.self_contact.smoothing = self.number("smoothing", 0.1 * sc.self_contact.law.thickness);
    if (sc.self_contact.exclude <= sc.self_contact.law.thickness)
      self.fail("exclude",
                "expected more than the contact thickness (" + std::to_string(sc.self_contact.law.thickness) + " m)");
  }
}

// A body that starts inside a collider meets a force of its whole penetration at once, and the
// integrators crawl (IDA at 1e-9 s steps) or fail: an error naming the collider and the nodes.
// Within the contact thickness the law is as smooth as anywhere (a body may start resting there).
void check_initial_contact(const Section& root, const Scene& sc) {
  const Section contact = root.table("contact");
  const Points& x = sc.initial_positions.size() ? sc.initial_positions : sc.mesh.rest_positions();
  for (std::size_t k = 0; k < sc.colliders.size(); ++k) {
    const Collider& C = sc.colliders[k];
    const ColliderPose P = C.pose(0.0, sc.skeleton.get());
    int inside = 0;
    double deepest = 0;
    for (int n = 0; n < x.cols(); ++n) {
      const double d = C.distance(P, x.col(n), nullptr, nullptr);
      if (d < -C.law.thickness) {
        ++inside;
        deepest = std::min(deepest, d);
      }
    }
    if (inside == 0) continue;
    char where[160];
    if (C.shape.kind == ColliderShape::Kind::plane)
      std::snprintf(where, sizeof where, "below the plane through [%g, %g, %g] with normal [%g, %g, %g]", P.b.x(),
                    P.b.y(), P.b.z(), P.A(0, 2), P.A(1, 2), P.A(2, 2));
    else
      std::snprintf(where, sizeof where, "inside this %s at t = 0", C.shape.name());
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  "%d of %d nodes start more than the contact thickness (%g m) %s (the deepest %.3g m; expected the "
                  "body outside it: move mesh.center or the collider)",
                  inside, static_cast<int>(x.cols()), C.law.thickness, where, -deepest);
    if (C.name == "contact.ground") contact.fail("ground", buf);
    if (C.name.rfind("contact.plane", 0) == 0)
      contact.tables("plane").at(k - (sc.colliders[0].name == "contact.ground")).fail("point", buf);
    root.tables("collider")
        .at(k - (sc.colliders.size() - root.tables("collider").size()))
        .fail(C.shape.kind == ColliderShape::Kind::plane ? "center" : "shape", buf);
  }
}

}  // namespace

namespace {

// The [[boundary]]s in file order; returns which boundary drives each node (-1: none).
std::vector<int> parse_boundaries(const Section& root, Scene& sc) {
  std::vector<int> driven_by(sc.mesh.num_nodes(), -1);
  for (const Section& b : root.tables("boundary")) {
    sc.boundary.push_back(parse_boundary(b, sc.mesh));
    const int k = static_cast<int>(sc.boundary.size()) - 1;
    for (int v : sc.boundary.back().nodes) {
      // Supports that hold some components may share a node (a corner on two symmetry planes);
      // a driver of all three components owns its nodes.
      if (driven_by[v] >= 0 && (sc.boundary.back().held.empty() || sc.boundary[driven_by[v]].held.empty()))
        b.fail("select",
               "node " + std::to_string(v) + " is already driven by boundary[" + std::to_string(driven_by[v]) +
                   "] (expected each node in at most one [[boundary]], unless both hold only some components)");
      driven_by[v] = k;
    }
  }
  return driven_by;
}

// [integrator]: its kind (from the registry) and its options, and the kinds the material allows.
void parse_integrator(const Section& root, Scene& sc) {
  const Section in = root.table("integrator");
  IntegratorSpec& ig = sc.integrator;
  std::vector<std::pair<std::string, IntegratorKind>> kinds;
  for (const IntegratorEntry& e : integrator_registry()) kinds.emplace_back(e.name, e.kind);
  ig.kind = parse_choice(in, "kind", ig.kind, kinds);
  for (const IntegratorEntry& e : integrator_registry()) e.parse(in, ig.kind, ig);
  const bool mass_spring = sc.material.model == MaterialModel::mass_spring;
  if (ig.kind == IntegratorKind::xpbd && mass_spring)
    in.fail("kind", "\"xpbd\" needs a tet material (expected material.model other than \"mass_spring\")");
  if (ig.kind == IntegratorKind::mass_spring && !mass_spring)
    in.fail("kind", "\"mass_spring\" is Hong et al.'s step for material.model = \"mass_spring\"");
  if (std::isinf(sc.material.lambda) && ig.kind != IntegratorKind::xpbd)
    root.table("material").fail("nu", "nu = 0.5 (incompressible) needs integrator.kind = \"xpbd\" (expected nu < 0.5)");
}

// Limits before work: a frame count that the frame times alone would not fit, and fixed steps
// that could not reach the end within integrator.max_steps.
void check_run_length(const Section& fr, const Section& in, const Scene& sc) {
  const IntegratorSpec& ig = sc.integrator;
  const double frames = std::floor(sc.frames.duration * sc.frames.rate + 1e-9) + 1;
  if (frames > 1e8) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "%g s at frames.rate = %g makes %.3g frames (expected at most 1e8)",
                  sc.frames.duration, sc.frames.rate, frames);
    fr.fail(fr.has("duration") ? "duration" : "rate", buf);
  }
  if (sc.frames.duration > 0 && sc.frames.duration * sc.frames.rate < 1 - 1e-9) {
    char buf[240];
    std::snprintf(buf, sizeof buf,
                  "%g frames per second put the frame after t = 0 at %g s, past the run's end (frames.duration = %g "
                  "s): only the start would be written (expected a rate of at least 1/duration)",
                  sc.frames.rate, 1 / sc.frames.rate, sc.frames.duration);
    fr.fail(fr.has("rate") ? "rate" : "duration", buf);
  }
  double dt = 0;
  long max_steps = 0;
  if (ig.kind == IntegratorKind::backward_euler || ig.kind == IntegratorKind::semi_implicit) {
    dt = ig.backward_euler.dt;
    max_steps = ig.backward_euler.max_steps;
  } else if (ig.kind == IntegratorKind::xpbd) {
    dt = ig.xpbd.dt;
    max_steps = ig.xpbd.max_steps;
  } else if (ig.kind == IntegratorKind::mass_spring) {
    dt = ig.hong.dt;
    max_steps = ig.hong.max_steps;
  }
  if (dt > 0 && sc.frames.duration > 0 && dt > sc.frames.duration) {
    char buf[240];
    std::snprintf(buf, sizeof buf,
                  "%g s is longer than the run (frames.duration = %g s): not one step would be taken (expected dt "
                  "at most the duration)",
                  dt, sc.frames.duration);
    in.fail("dt", buf);
  }
  if (dt > 0 && sc.frames.duration / dt > static_cast<double>(max_steps)) {
    char buf[240];
    std::snprintf(buf, sizeof buf,
                  "%g s makes %.3g steps over frames.duration = %g s, more than integrator.max_steps = %ld (expected a "
                  "larger dt or a shorter run)",
                  dt, sc.frames.duration / dt, sc.frames.duration, max_steps);
    in.fail("dt", buf);
  }
}

// [frames]: a rate and duration (dynamics) or a count (statics), as the integrator needs.
void parse_frames(const Section& root, Scene& sc) {
  const Section fr = root.table("frames");
  const bool statics = sc.integrator.kind == IntegratorKind::statics;
  if (fr.has("count") && (fr.has("rate") || fr.has("duration")))
    fr.fail("count", "give either count (statics) or rate and duration, not both");
  sc.frames.rate = fr.number("rate", sc.frames.rate);
  sc.frames.duration = fr.number("duration", sc.frames.duration);
  sc.frames.count = static_cast<int>(fr.integer("count", 0));
  if (statics != (sc.frames.count > 0))
    fr.fail(statics ? "count" : "rate",
            statics ? "a static run needs frames.count (load increments)"
                    : "frames.count is for statics; a dynamic run needs frames.rate and frames.duration");
  if (!statics) check_run_length(fr, root.table("integrator"), sc);
}

// [character]: a rigged glTF's mesh, zones and render mesh (the skeleton comes after the
// boundaries, which its bones must not drive twice); it stands in for [mesh] and [skeleton].
std::optional<Character> parse_character_block(const Section& root, Scene& sc, const Mesh* filled) {
  const Section c = root.table("character");
  if (!c.exists()) return std::nullopt;
  for (const char* other : {"mesh", "skeleton"})
    if (root.table(other).exists())
      root.fail(other, std::string("a [character] brings its own mesh and skeleton (expected no [") + other + "])");
  const double duration = root.table("frames").number("duration", sc.frames.duration);
  Character ch = parse_character(c, sc.file, duration, filled);
  sc.mesh = std::move(ch.mesh);
  sc.render = ch.render;
  return ch;
}

std::shared_ptr<Skeleton> character_skeleton(const Section& c, const Character& ch, const std::vector<int>& driven_by) {
  for (const BoneSpec& b : ch.bones)
    for (int v : b.nodes)
      if (driven_by[v] >= 0)
        c.fail("file", "node " + std::to_string(v) + " follows joint \"" + b.name + "\" and boundary[" +
                           std::to_string(driven_by[v]) + "] both (expected each node driven once)");
  return std::make_shared<Skeleton>(ch.bones);
}

}  // namespace

Scene parse_scene(SceneFile file, const Mesh* character_mesh) {
  Scene sc{std::move(file),
           {},
           {},
           {},
           Eigen::Vector3d(0, 0, -9.81),
           0.0,
           {},
           {},
           {},
           {},
           {},
           Eigen::Vector3d::Zero(),
           {},
           {},
           {},
           {},
           0.0,
           true,
           {},
           {},
           {},
           {},
           {},
           {},
           1.0,
           {}};
  const Section root = sc.file.root();
  const std::optional<Character> character = parse_character_block(root, sc, character_mesh);
  if (!character) {
    Section mesh = root.table("mesh");
    if (!mesh.exists()) root.fail("mesh", "missing, expected a [mesh] table with a shape or a file (or a [character])");
    sc.mesh = mesh_from_scene(mesh, sc.file);
  }
  sc.material = parse_material(root.table("material"));
  if (std::string note = material_note(sc.material); !note.empty()) sc.notes.push_back(std::move(note));
  ZoneChoice zone_choice = parse_zones(root.table("zones"), sc.mesh, sc.file, sc.material.model == MaterialModel::cnh);
  sc.zones = zone_choice.zones;  // [[material.region]] may name them
  sc.keep_zones = root.table("zones").boolean("keep", true);
  parse_material_regions(root.table("material"), sc);
  sc.zone_restore_time = root.table("zones").number("restore_time");
  const std::vector<int> driven_by = parse_boundaries(root, sc);
  sc.skeleton = character ? character_skeleton(root.table("character"), *character, driven_by)
                          : parse_skeleton(root.table("skeleton"), sc.file, sc.mesh, driven_by);
  settle_zones(root.table("zones"), std::move(zone_choice), sc);

  const Section forces = root.table("forces");
  sc.gravity = forces.vec3("gravity", sc.gravity);
  sc.gravity_ramp = forces.number("gravity_ramp");
  parse_colliders(root, sc);
  for (const Section& l : root.tables("load")) parse_load(l, sc.mesh, sc);
  const Section damping = root.table("damping");
  // Rayleigh damping a body can have: alpha = 1e6 1/s relaxes velocities in a microsecond, beta =
  // 1e3 s overdamps every mode above 0.002 rad/s; 1e300 stopped IDA at t = 0 naming no key.
  sc.damping.alpha = damping.number("alpha");
  sc.damping.beta = damping.number("beta", 0.0);
  const Section initial = root.table("initial");
  sc.initial_velocity = initial.vec3("velocity");
  parse_flatten(initial, sc);
  parse_start_from(initial, sc);
  parse_start_displacement(initial, sc);
  parse_integrator(root, sc);
  parse_muscles(root, sc);
  // IDA starts from a consistent state: zones flattened to volume 0 cannot meet their rest
  // volumes at t = 0 (it would fail there with IDA_CONV_FAIL and no hint).
  if (sc.initial_positions.size() && !sc.zones.empty() && sc.keep_zones && sc.zone_restore_time == 0 &&
      sc.integrator.kind == IntegratorKind::ida)
    check_start_volumes(root.table("initial"), sc);
  parse_frames(root, sc);
  check_initial_contact(root, sc);

  const Section out = root.table("output");
  const std::string stem = std::filesystem::path(sc.file.name()).stem().string();
  sc.output.path = out.string("path", "out/" + (stem.empty() ? std::string("scene") : stem) + ".h5");
  sc.output.pressure = out.boolean("pressure", false);

  sc.file.check_unknown_keys();
  return sc;
}

const char* to_string(MaterialModel m) { return name_of(kModels, m); }

std::string material_note(const MaterialSpec& m) {
  if (m.model != MaterialModel::snh) return "";
  // Incompressible uniaxial tension: (4/3) I / (I + 1) times neo-Hooke's nominal stress,
  // I = l^2 + 2 / l (tests/test_materials.cpp: SnhInIncompressibleUniaxialTension...).
  auto stiffer = [](double l) {
    const double I = l * l + 2 / l;
    return 100.0 * (4.0 / 3.0 * I / (I + 1) - 1.0);
  };
  char line[512];
  std::snprintf(line, sizeof line,
                "material.model = \"snh\" is Smith et al. 2018's stable neo-Hookean, run with mu' = 4/3 mu = %g Pa "
                "and lambda' = lambda + 5/6 mu = %g Pa: its small-strain shear modulus is mu = %g Pa, but in "
                "incompressible uniaxial tension it is stiffer than neo-Hooke with that mu, by %.1f%% at stretch 1.2, "
                "%.1f%% at 1.5 and %.1f%% at 2 (docs/scenes.md)",
                4.0 / 3.0 * m.mu, m.lambda + 5.0 / 6.0 * m.mu, m.mu, stiffer(1.2), stiffer(1.5), stiffer(2.0));
  return line;
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  return parse_scene(SceneFile::load(path, overrides));
}

}  // namespace isochor
