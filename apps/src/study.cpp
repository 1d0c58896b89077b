#include "isochor/app/study.hpp"

#include <sys/resource.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "isochor/base/error.hpp"
#include "isochor/core/input_file.hpp"
#include "isochor/core/mesh.hpp"
#include "isochor/core/output_reader.hpp"
#include "isochor/core/process.hpp"
#include "isochor/core/scene_file.hpp"

extern char** environ;

namespace isochor {

namespace {
std::string number_text(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}
std::string label_of(const std::string& method, const std::vector<std::pair<std::string, double>>& sweep) {
  std::string l = method;
  for (const auto& [key, value] : sweep) {
    char b[64];
    std::snprintf(b, sizeof b, "%g", value);
    l += "__" + key.substr(key.rfind('.') + 1) + "_" + b;
  }
  return l;
}
std::string toml_string(const std::string& v) {
  std::string out(1, '"');
  for (char c : v) {
    if (static_cast<unsigned char>(c) < 32) {  // TOML basic strings hold no control characters
      char u[8];
      std::snprintf(u, sizeof u, "\\u%04x", static_cast<unsigned char>(c));
      out += u;
      continue;
    }
    if (c == '"' || c == '\\') out.push_back('\\');
    out.push_back(c);
  }
  out.push_back('"');
  return out;
}

// [observable]: one number per case, measured by the report (tools/study_report.py) and kept in
// the study's directory as observable.toml, so that `isochor report DIR` finds it too.
std::string parse_observable(const Section& o) {
  if (!o.exists()) return "";
  const std::string kind = o.string("kind", "");
  if (kind.empty()) o.fail("kind", "missing, expected \"point\" or \"set\"");
  std::string name = o.string("name", "observable");
  if (name.empty() || std::any_of(name.begin(), name.end(), [](unsigned char c) { return c < 32; }))
    o.fail("name", "expected a non-empty name without control characters");
  std::ostringstream t;
  t << "name = " << toml_string(name) << "\nkind = " << toml_string(kind) << "\n";
  if (kind == "point") {
    const auto p = o.vec3_opt("point");
    if (!p) o.fail("point", "missing, expected [x, y, z]: the rest position whose nearest node is measured");
    t << "point = [" << number_text((*p)[0]) << ", " << number_text((*p)[1]) << ", " << number_text((*p)[2]) << "]\n";
  } else {
    const std::string set = o.string("set", "");
    if (set.empty()) o.fail("set", "missing, expected the name of a node set of the mesh");
    t << "set = " << toml_string(set) << "\n";
  }
  t << "component = " << toml_string(o.string("component")) << "\n";
  t << "frame = " << o.integer("frame") << "\n";
  if (const auto r = o.number_opt("reference")) t << "reference = " << number_text(*r) << "\n";
  return t.str();
}
}  // namespace

namespace {

// A study's scene is refused as the scene of a run would be (missing, a directory, a device, too
// large), naming the study's key, before any case starts.
void check_scene_file(const Section& section, const std::filesystem::path& scene) {
  try {
    check_input_file(scene.string(), "a scene file in TOML", input_limits::kScene);
  } catch (const Error& e) {
    section.fail("scene", e.what());
  }
}

}  // namespace

Study load_study(const std::string& path, const std::vector<std::string>& overrides) {
  SceneFile f = SceneFile::load(path, overrides, study_keys());
  const Section root = f.root();
  Study s;
  s.file = path;
  const Section st = root.table("study");
  const std::string scene = st.string("scene", "");
  if (scene.empty()) st.fail("scene", "missing, expected the base scene file (relative to the study)");
  s.scene = std::filesystem::path(path).parent_path() / scene;
  check_scene_file(st, s.scene);
  const std::string stem = std::filesystem::path(path).stem().string();
  s.output = st.string("output", "out/studies/" + stem);
  s.jobs = static_cast<int>(st.integer("jobs"));
  s.kind = st.string("kind", "work_precision");
  s.observable = parse_observable(root.table("observable"));
  const std::vector<std::string> base = st.strings("set");
  const Section ref = root.table("reference");
  StudyCase r{"reference", "reference", base, {}, {}};
  const std::vector<std::string> ref_set =
      ref.exists() ? ref.strings("set")
      : s.kind == "convergence"
          ? std::vector<std::string>{}  // the base scene as it is
          : std::vector<std::string>{"integrator.kind=ida", "integrator.rtol=1e-10", "integrator.atol=1e-12"};
  r.overrides.insert(r.overrides.end(), ref_set.begin(), ref_set.end());
  s.cases.push_back(r);
  for (const Section& m : root.tables("method")) {
    const std::string name = m.string("name", "");
    if (name.empty()) m.fail("name", "missing, expected the method's name");
    if (name == "reference" || name.find_first_of("/ ,") != std::string::npos)
      m.fail("name", "expected a name without '/', ' ' or ',' other than \"reference\"");
    std::vector<std::string> set = base;
    for (const std::string& o : m.strings("set")) set.push_back(o);
    std::filesystem::path own_scene;
    if (m.has("scene")) {
      own_scene = std::filesystem::path(path).parent_path() / m.string("scene", "");
      check_scene_file(m, own_scene);
    }
    // Sweeps: { key = [values] }, the cartesian product of all keys.
    const Section sw = m.table("sweep");
    std::vector<std::pair<std::string, std::vector<double>>> axes;
    for (const std::string& key : sw.keys()) {
      const auto values = sw.numbers(key);
      if (values.empty()) sw.fail(key, "expected a non-empty list of values");
      axes.emplace_back(key, values);
    }
    std::vector<std::vector<std::pair<std::string, double>>> points{{}};
    for (const auto& [key, values] : axes) {
      std::vector<std::vector<std::pair<std::string, double>>> next;
      for (const auto& p : points)
        for (double v : values) {
          auto q = p;
          q.emplace_back(key, v);
          next.push_back(q);
        }
      points.swap(next);
    }
    for (const auto& p : points) {
      StudyCase c{name, label_of(name, p), set, p, own_scene};
      for (const auto& [key, value] : p) c.overrides.push_back(key + "=" + number_text(value));
      s.cases.push_back(c);
    }
  }
  if (s.cases.size() < 2) root.fail("method", "missing, expected at least one [[method]]");
  f.check_unknown_keys();
  return s;
}

namespace {

struct Outcome {
  int status = 0;
  double cpu = 0;
};

// Runs one case in its own process: one OpenMP and BLAS thread (cases run side by side), output
// and messages into the study's cases/ directory. Returns the exit status and CPU seconds.
Outcome run_case(const Study& s, const StudyCase& c, const std::string& exe) {
  const auto dir = s.output / "cases";
  // The study owns its directory: a case run again replaces its file.
  std::vector<std::string> args{exe,
                                "run",
                                (c.scene.empty() ? s.scene : c.scene).string(),
                                "-q",
                                "--overwrite",
                                "-o",
                                (dir / (c.label + ".h5")).string()};
  for (const std::string& o : c.overrides) {
    args.push_back("--set");
    args.push_back(o);
  }
  // A case is its own program, not part of an MPI job that `isochor study --mpi` runs in: it
  // gets none of mpirun's variables (one that initialises MPI itself, for linear_solver = "amg",
  // would otherwise try to join the job).
  const auto drop = [](const std::string& v) {
    return v.rfind("OMPI_", 0) == 0 || v.rfind("PMIX_", 0) == 0 || v.rfind("PMI_", 0) == 0 ||
           v.rfind("OMP_NUM_THREADS=", 0) == 0 || v.rfind("OPENBLAS_NUM_THREADS=", 0) == 0;
  };
  pid_t pid;
  Outcome out;
  if (spawn_logged(args, (dir / (c.label + ".log")).string(), drop, {"OMP_NUM_THREADS=1", "OPENBLAS_NUM_THREADS=1"},
                   pid) != 0) {
    out.status = 127;
    return out;
  }
  int status = 0;
  rusage ru{};
  wait4(pid, &status, 0, &ru);
  out.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  out.cpu = ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 + ru.ru_stime.tv_sec + ru.ru_stime.tv_usec * 1e-6;
  std::ofstream(dir / (c.label + ".cpu")) << number_text(out.cpu) << "\n" << out.status << "\n";
  return out;
}

std::string last_line(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

std::string csv_field(std::string s) {
  for (char& ch : s)
    if (ch == '"') ch = '\'';
  return "\"" + s + "\"";
}

// Runs the cases `which` (indices into s.cases), `jobs` at a time; with `resume`, a case that
// finished before (its .cpu file is there) is not run again. Returns how many of them failed.
int run_cases(const Study& s, const std::vector<std::size_t>& which, const std::string& exe, bool resume, bool progress,
              int jobs) {
  std::filesystem::create_directories(s.output / "cases");
  std::atomic<std::size_t> next{0};
  std::atomic<int> done{0}, failed{0};
  std::mutex print;
  auto worker = [&]() {
    for (std::size_t i = next++; i < which.size(); i = next++) {
      const StudyCase& c = s.cases[which[i]];
      const auto cpu = s.output / "cases" / (c.label + ".cpu");
      Outcome o;
      const bool skip = resume && std::filesystem::exists(cpu);
      if (skip) {
        std::ifstream in(cpu);
        in >> o.cpu >> o.status;
      } else {
        o = run_case(s, c, exe);
      }
      const int d = ++done;
      failed += o.status != 0;
      if (progress) {
        std::lock_guard<std::mutex> lock(print);
        std::fprintf(stderr, "[%d/%zu] %-40s %s (%.1f s CPU)%s\n", d, which.size(), c.label.c_str(),
                     o.status == 0 ? "ok" : "FAILED", o.cpu, skip ? ", done before" : "");
      }
    }
  };
  // The reference is started first, but not alone: errors are computed once every case is done,
  // so the other core need not wait for it (the reference is usually the longest case).
  std::vector<std::thread> pool;
  for (int j = 0; j < jobs; ++j) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  return failed;
}

}  // namespace

int run_study(const Study& s, const std::string& exe, bool resume, bool progress) {
  std::vector<std::size_t> all(s.cases.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  save_case_list(s);
  const int failed = run_cases(s, all, exe, resume, progress, s.jobs);
  write_study_results(s);
  return failed;
}

int run_study_case(const Study& s, const std::string& label, const std::string& exe, bool progress) {
  for (std::size_t i = 0; i < s.cases.size(); ++i)
    if (s.cases[i].label == label) {
      save_case_list(s);
      return run_cases(s, {i}, exe, false, progress, 1) == 0 ? 0 : 1;
    }
  throw Error(s.file + ": no case " + label + " (`isochor study " + s.file + " --list` lists them)");
}

int run_study_queue(const Study& s, const std::string& exe, const std::function<int()>& next_case, bool progress) {
  std::filesystem::create_directories(s.output / "cases");
  save_case_list(s);
  int failed = 0;
  for (int i = next_case(); i >= 0; i = next_case()) {
    if (i >= static_cast<int>(s.cases.size())) throw Error(s.file + ": case " + std::to_string(i) + " does not exist");
    failed += run_cases(s, {static_cast<std::size_t>(i)}, exe, true, progress, 1);
  }
  return failed;
}

void save_case_list(const Study& s) {
  std::filesystem::create_directories(s.output);
  const auto path = s.output / "cases.csv", tmp = s.output / ("cases.csv." + std::to_string(::getpid()));
  {
    std::ofstream out(tmp);
    out << "method,label,sweep\n";
    for (const StudyCase& c : s.cases) {
      std::string sweep;
      for (const auto& [key, value] : c.sweep) sweep += (sweep.empty() ? "" : ";") + key + "=" + number_text(value);
      out << c.method << "," << c.label << "," << sweep << "\n";
    }
    if (!out) throw Error(tmp.string() + ": cannot be written");
  }
  std::filesystem::rename(tmp, path);  // whole or not at all, whichever process writes it last
  if (s.observable.empty()) return;
  const auto obs = s.output / "observable.toml", obs_tmp = s.output / ("observable.toml." + std::to_string(::getpid()));
  {
    std::ofstream out(obs_tmp);
    out << s.observable;
    if (!out) throw Error(obs_tmp.string() + ": cannot be written");
  }
  std::filesystem::rename(obs_tmp, obs);
}

Study load_case_list(const std::filesystem::path& dir) {
  const auto path = dir / "cases.csv";
  std::ifstream in(path);
  if (!in) throw Error(dir.string() + ": no cases.csv (expected the output directory of `isochor study`)");
  Study s;
  s.file = path.string();
  s.output = dir;
  std::string line;
  std::getline(in, line);  // the header
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty()) continue;
    std::stringstream fields(line);
    StudyCase c;
    std::string sweep;
    if (!std::getline(fields, c.method, ',') || !std::getline(fields, c.label, ','))
      throw Error(path.string() + ":" + std::to_string(row) + ": expected method,label,sweep");
    std::getline(fields, sweep);
    std::stringstream items(sweep);
    for (std::string item; std::getline(items, item, ';');) {
      const auto eq = item.find('=');
      if (eq == std::string::npos)
        throw Error(path.string() + ":" + std::to_string(row) + ": sweep " + item + ": expected key=value");
      c.sweep.emplace_back(item.substr(0, eq), std::strtod(item.c_str() + eq + 1, nullptr));
    }
    s.cases.push_back(c);
  }
  if (s.cases.empty()) throw Error(path.string() + ": lists no cases");
  return s;
}

namespace {

// The reference run's frames, and the norms its errors are measured against (the displacement
// from rest summed over frames; the centroid's path from its start).
struct Reference {
  std::unique_ptr<RunFile> file;
  std::vector<Points> x;
  std::vector<Eigen::Vector3d> centroid;  // of the nodes, per frame
  double den = 0, centroid_den = 0;
};

Reference load_reference(const std::filesystem::path& path) {
  Reference r;
  try {
    r.file = std::make_unique<RunFile>(path.string());
    const Points X = r.file->rest_positions();
    for (int k = 0; k < r.file->num_frames(); ++k) {
      r.x.push_back(r.file->positions(k));
      r.den += (r.x.back() - X).squaredNorm();
      r.centroid.push_back(r.x.back().rowwise().mean());
      r.centroid_den += (r.centroid.back() - r.centroid.front()).squaredNorm();
    }
  } catch (const Error& e) {
    // No usable reference (failed, or not run): every case's error is left blank, and said so.
    std::fprintf(stderr, "isochor study: no reference to measure errors against (%s)\n", e.what());
    return Reference{};
  }
  return r;
}

// The worst relative zone-volume error over the frames; a start away from the rest volume
// (initial.flatten: volume 0) has no first frame to measure against: its last frame's total
// volume against the rest volume.
double worst_volume_error(const RunFile& f) {
  const auto v = f.volumes();
  const double rest = surface_volume(f.rest_positions(), f.surface());
  if (!v.empty() && std::abs(v[0][0] / rest - 1) > 1e-6) return std::abs(v.back()[0] / rest - 1);
  double vol = 0;
  for (const auto& row : v)
    for (std::size_t z = 0; z < row.size(); ++z) vol = std::max(vol, std::abs(row[z] / v[0][z] - 1));
  return vol;
}

// What results.csv says of one case's run.
struct CaseMeasures {
  int frames = 0;
  double wall = NAN, steps = NAN, err = NAN, vol = NAN, cerr = NAN, shape = NAN, inverted = NAN;
};

// Filled as far as the file can be read (a half-written file keeps what was measured before).
void measure_case(const std::filesystem::path& path, const Reference& ref, CaseMeasures& m) {
  RunFile f(path.string());
  m.frames = f.num_frames();
  const auto totals = f.stat_totals();
  if (totals.count("wall_seconds")) m.wall = totals.at("wall_seconds");
  if (totals.count("steps")) m.steps = totals.at("steps");
  if (m.frames > 0) m.shape = rest_shape_error(f.rest_positions(), f.positions(m.frames - 1));
  const auto series = f.stat_series();
  if (auto it = series.find("inverted_tets"); it != series.end() && !it->second.empty()) m.inverted = it->second.back();
  m.vol = worst_volume_error(f);
  if (!ref.file || ref.den <= 0 || m.frames == 0 || f.num_nodes() != ref.file->num_nodes()) return;  // not another mesh
  double num = 0, cnum = 0;
  const int n = std::min(m.frames, static_cast<int>(ref.x.size()));
  for (int k = 0; k < n; ++k) {
    const Points x = f.positions(k);
    num += (x - ref.x[k]).squaredNorm();
    cnum += (Eigen::Vector3d(x.rowwise().mean()) - ref.centroid[k]).squaredNorm();
  }
  m.err = std::sqrt(num / ref.den);
  if (ref.centroid_den > 0) m.cerr = std::sqrt(cnum / ref.centroid_den);
  return;
}

}  // namespace

void write_study_results(const Study& s) {
  const auto dir = s.output / "cases";
  const Reference ref = load_reference(dir / "reference.h5");
  std::ofstream csv(s.output / "results.csv");
  csv << "method,label,sweep,status,reason,frames,frames_expected,cpu_seconds,wall_seconds,steps,error_l2,"
         "volume_error,error_centroid,shape_error,inverted_tets\n";
  for (const StudyCase& c : s.cases) {
    double cpu = NAN;
    int status = -1;
    const bool ran = std::filesystem::exists(dir / (c.label + ".cpu"));
    if (ran) {
      std::ifstream in(dir / (c.label + ".cpu"));
      in >> cpu >> status;
    }
    std::string sweep;
    for (const auto& [key, value] : c.sweep) sweep += (sweep.empty() ? "" : ";") + key + "=" + number_text(value);
    std::string reason = !ran ? "not run yet" : status == 0 ? "" : last_line(dir / (c.label + ".log"));
    CaseMeasures m;
    try {
      measure_case(dir / (c.label + ".h5"), ref, m);
    } catch (const Error& e) {
      if (reason.empty()) reason = e.what();
    }
    const char* state = !ran ? "missing" : status == 0 ? "ok" : "failed";
    csv << c.method << "," << c.label << "," << csv_field(sweep) << "," << state << "," << csv_field(reason) << ","
        << m.frames << "," << (ref.file ? ref.file->num_frames() : 0) << "," << number_text(cpu) << ","
        << number_text(m.wall) << "," << number_text(m.steps) << "," << number_text(m.err) << "," << number_text(m.vol)
        << "," << number_text(m.cerr) << "," << number_text(m.shape) << "," << number_text(m.inverted) << "\n";
  }
}

}  // namespace isochor
