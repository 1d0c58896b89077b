// isochor's Python module, `_isochor` (wrapped by the package python/isochor/): scenes from a
// file or a dict with overrides, runs with a per-frame callback that receives NumPy arrays and
// may stop the run, and studies. C++'s isochor::Error arrives as isochor.Error with the same
// one-line message that the command line prints after "isochor: ".
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <dlfcn.h>

#include <filesystem>
#include <optional>
#include <sstream>
#include <variant>
#include <toml++/toml.h>

#include "isochor/base/error.hpp"
#include "isochor/core/output.hpp"
#include "isochor/scene/scene.hpp"
#include "isochor/scene/zones_setup.hpp"
#include "isochor/app/install.hpp"
#include "isochor/app/run.hpp"
#include "isochor/app/study.hpp"

namespace py = pybind11;
using namespace isochor;

namespace {

// ---- Python values to TOML ------------------------------------------------------------------

toml::table to_table(py::handle d, const std::string& where, int depth);

// Deeper nesting is refused: a scene is a few levels deep, and a dict or list that contains
// itself would recurse without end.
constexpr int kMaxDepth = 64;
void check_depth(int depth, const std::string& where) {
  if (depth > kMaxDepth)
    throw Error(where + ": nested more than " + std::to_string(kMaxDepth) +
                " levels deep (expected a scene's tables and lists; does a dict or list contain itself?)");
}

std::string type_name(py::handle v) { return py::str(py::type::of(v).attr("__name__")).cast<std::string>(); }

// One TOML value (a plain function, not a template over sinks: that recursed without end).
using TomlValue = std::variant<bool, int64_t, double, std::string, toml::array, toml::table>;

// The TOML value of a Python value (`where` names it in errors).
TomlValue to_toml(py::handle v, const std::string& where, int depth = 0) {
  check_depth(depth, where);
  if (py::isinstance<py::array>(v)) return to_toml(v.attr("tolist")(), where, depth + 1);  // nested lists
  if (py::isinstance<py::bool_>(v) ||
      (py::hasattr(v, "dtype") && py::str(v.attr("dtype").attr("kind")).cast<std::string>() == "b"))
    return v.cast<bool>();
  if (py::isinstance<py::int_>(v) || (py::hasattr(v, "__index__") && !py::isinstance<py::float_>(v))) {
    try {
      return static_cast<int64_t>(py::int_(py::reinterpret_borrow<py::object>(v)).cast<long long>());
    } catch (const py::cast_error&) {
      throw Error(where + ": " + py::repr(v).cast<std::string>() +
                  " does not fit in a 64-bit integer (expected -2**63 to 2**63 - 1, or a float)");
    }
  }
  if (py::isinstance<py::float_>(v) || py::hasattr(v, "__float__"))
    return py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>();
  if (py::isinstance<py::str>(v) || py::hasattr(v, "__fspath__"))
    return py::str(py::module_::import("os").attr("fspath")(v)).cast<std::string>();
  if (py::isinstance<py::dict>(v)) return to_table(v, where, depth + 1);
  if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
    toml::array a;
    int i = 0;
    for (py::handle item : v)
      std::visit([&](auto&& x) { a.push_back(std::move(x)); },
                 to_toml(item, where + "[" + std::to_string(i++) + "]", depth + 1));
    return a;
  }
  throw Error(where + ": expected a number, string, boolean, list or dict, got a " + type_name(v));
}

toml::table to_table(py::handle d, const std::string& where, int depth) {
  check_depth(depth, where);
  toml::table t;
  for (auto [k, v] : py::reinterpret_borrow<py::dict>(d)) {
    if (!py::isinstance<py::str>(k))
      throw Error(where + ": keys must be strings, got " + py::repr(k).cast<std::string>());
    const std::string key = k.cast<std::string>();
    std::visit([&](auto&& x) { t.insert_or_assign(key, std::move(x)); },
               to_toml(v, where.empty() ? key : where + "." + key, depth + 1));
  }
  return t;
}

// Overrides as `--set` takes them: "key=value" strings as they are, or a dict of dotted keys (a
// dict value stands for its keys under the key) to TOML values.
void add_overrides(py::handle o, const std::string& prefix, std::vector<std::string>& out, int depth = 0) {
  if (o.is_none()) return;
  check_depth(depth, "overrides" + (prefix.empty() ? std::string() : " " + prefix));
  if (py::isinstance<py::str>(o)) {
    out.push_back(o.cast<std::string>());
  } else if (py::isinstance<py::dict>(o)) {
    for (auto [k, v] : py::reinterpret_borrow<py::dict>(o)) {
      const std::string key = prefix + py::str(k).cast<std::string>();
      if (py::isinstance<py::dict>(v)) {
        add_overrides(v, key + ".", out, depth + 1);
        continue;
      }
      std::ostringstream s;
      s << key << '=';
      std::visit(
          [&](const auto& x) {
            using T = std::decay_t<decltype(x)>;
            if constexpr (std::is_same_v<T, toml::array> || std::is_same_v<T, toml::table>)
              s << x;
            else
              s << toml::value<T>(x);  // TOML's own spelling: true, quoted strings, ...
          },
          to_toml(v, "--set " + key));
      out.push_back(s.str());
    }
  } else {
    for (py::handle item : o) add_overrides(item, prefix, out, depth + 1);  // a list of "key=value"
  }
}

std::vector<std::string> overrides_of(py::handle o) {
  std::vector<std::string> out;
  add_overrides(o, "", out);
  return out;
}

// ---- NumPy views of C++ data ------------------------------------------------------------------

py::array_t<double> points_array(const Points& p) {  // (N,3), a copy
  py::array_t<double> a({static_cast<py::ssize_t>(p.cols()), py::ssize_t{3}});
  std::copy(p.data(), p.data() + p.size(), a.mutable_data());
  return a;
}

py::array_t<double> vector_array(const std::vector<double>& v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}

template <std::size_t K>
py::array_t<int> index_array(const std::vector<std::array<int, K>>& rows) {
  py::array_t<int> a({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(K)});
  int* d = a.mutable_data();
  for (const auto& r : rows)
    for (int x : r) *d++ = x;
  return a;
}

py::dict frame_dict(int index, const Frame& f) {
  py::dict d;
  d["index"] = index;
  d["time"] = f.time;
  d["positions"] = points_array(*f.positions);
  if (f.velocities) d["velocities"] = points_array(*f.velocities);
  d["volumes"] = vector_array(f.volumes);
  d["energy"] = py::array_t<double>(3, f.energy.data());
  d["pressure"] = f.pressure ? py::object(vector_array(*f.pressure)) : py::object(py::none());
  d["multipliers"] = f.multipliers ? vector_array(*f.multipliers) : py::array_t<double>(0);
  d["loads"] = f.loads ? py::object(points_array(*f.loads)) : py::object(py::none());
  d["activation"] = f.activations ? py::object(vector_array(*f.activations)) : py::object(py::none());
  py::dict stats;
  for (const auto& [name, value] : f.stats) stats[py::str(name)] = value;
  d["stats"] = stats;
  return d;
}

// ---- Runs ------------------------------------------------------------------------------------

py::dict summary_dict(const RunSummary& r, bool stopped, const std::string& stop_reason) {
  py::dict d;
  d["output"] = r.output;
  d["frames"] = r.frames;
  d["stopped"] = stopped;
  d["stop_reason"] = stop_reason;
  d["resumed_from"] = r.resumed_from;
  d["already_finished"] = r.already_finished;
  const RunStats& s = r.stats;
  d["steps"] = s.steps;
  d["newton_iterations"] = s.newton_iterations;
  d["jacobian_evaluations"] = s.jacobian_evals;
  d["rejected_steps_newton"] = s.newton_failures;
  d["rejected_steps_error_test"] = s.error_test_failures;
  d["wall_seconds"] = s.wall_seconds;
  d["assembly_seconds"] = s.assembly_seconds;
  d["factorisation_seconds"] = s.factor_seconds;
  d["solve_seconds"] = s.solve_seconds;
  d["simbody_seconds"] = r.simbody_seconds;
  return d;
}

// Runs the scene with the GIL released; the callback (and a check for Ctrl-C) takes it at every
// frame. An exception raised by the callback (KeyboardInterrupt included) stops the run at that
// frame, which the file keeps (status "interrupted"), and is raised again here.
py::dict run(const Scene& scene, const std::string& output, const std::string& mode, bool progress, py::object on_frame,
             py::object activation) {
  RunOptions opt;
  opt.output = output;
  opt.progress = progress;
  if (mode == "create")
    opt.mode = OutputWriter::Mode::create;
  else if (mode == "overwrite")
    opt.mode = OutputWriter::Mode::overwrite;
  else if (mode == "resume")
    opt.mode = OutputWriter::Mode::resume;
  else
    throw Error("mode: expected create, overwrite or resume, got " + mode);
  std::optional<py::error_already_set> raised;
  bool stopped_by_callback = false;
  opt.on_frame = [&](int k, const Frame& f) {
    py::gil_scoped_acquire gil;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (on_frame.is_none()) return true;
      py::object r = on_frame(frame_dict(k, f));
      const bool boolean =
          py::isinstance<py::bool_>(r) ||
          (py::hasattr(r, "dtype") && py::str(r.attr("dtype").attr("kind")).cast<std::string>() == "b");
      if (!r.is_none() && !boolean) {
        PyErr_SetString(PyExc_TypeError, ("on_frame returned a " + type_name(r) +
                                          " (expected None or True to go on, False to stop the run)")
                                             .c_str());
        throw py::error_already_set();
      }
      if (!r.is_none() && !r.cast<bool>()) {
        stopped_by_callback = true;
        return false;
      }
      return true;
    } catch (py::error_already_set& e) {
      raised.emplace(std::move(e));
      return false;
    }
  };
  // The activation function (a list per call, one value per muscle): an exception it raises stops
  // the run as a solver failure would, and is raised again here.
  if (!activation.is_none())
    opt.activation = [&](double t) {
      py::gil_scoped_acquire gil;
      try {
        return activation(t).cast<std::vector<double>>();
      } catch (py::error_already_set& e) {
        raised.emplace(std::move(e));
      } catch (const py::cast_error&) {
        PyErr_SetString(PyExc_TypeError, "activation(t) returned something other than numbers");
        raised.emplace();
      }
      throw Error("the activation function raised an exception at t = " + std::to_string(t));
    };
  RunSummary r;
  std::string stop_reason;
  try {
    py::gil_scoped_release nogil;
    r = run_scene(scene, opt);
  } catch (const RunInterrupted& e) {
    if (raised) {
      py::error_already_set err = std::move(*raised);
      raised.reset();
      throw err;
    }
    if (!stopped_by_callback) throw;
    stop_reason = e.what();
    r = e.summary;
  } catch (const Error&) {
    if (!raised) throw;
    py::error_already_set err = std::move(*raised);
    raised.reset();
    throw err;
  }
  return summary_dict(r, !stop_reason.empty(), stop_reason);
}

std::shared_ptr<Scene> scene_from_dict(py::dict d, py::object overrides, const std::string& name,
                                       const std::string& directory) {
  std::ostringstream text;
  text << to_table(d, "", 0);
  return std::make_shared<Scene>(parse_scene(SceneFile::parse(text.str(), name, overrides_of(overrides), directory)));
}

void bind_error(py::module_& m) {
  // One isochor.Error for the compiled part and the pure-Python reader (isochor/_errors.py): its
  // class is kept for the interpreter's life (never released: no destructor runs at exit).
  static PyObject* const error = py::object(py::module_::import("isochor._errors").attr("Error")).release().ptr();
  m.attr("Error") = py::handle(error);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      PyErr_SetString(error, e.what());
    }
  });
}

// isochor.Scene: a loaded scene's name, text, mesh, zones, frame times and choices, read-only.
void bind_scene(py::module_& m) {
  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", "A loaded scene (isochor.load or isochor.scene): read-only")
      .def_property_readonly(
          "name", [](const Scene& s) { return s.file.name(); }, "The scene file's path as given (or the dict's name)")
      .def_property_readonly(
          "text", [](const Scene& s) { return s.file.text_as_run(); },
          "The scene as it runs, overrides applied, as TOML text")
      .def_property_readonly(
          "output_path", [](const Scene& s) { return s.output.path; },
          "output.path: where a run writes its HDF5 file by default")
      .def_property_readonly(
          "num_nodes", [](const Scene& s) { return s.mesh.num_nodes(); }, "The mesh's node count")
      .def_property_readonly(
          "num_tets", [](const Scene& s) { return s.mesh.num_tets(); }, "The mesh's tetrahedron count")
      .def_property_readonly(
          "rest_positions", [](const Scene& s) { return points_array(s.mesh.rest_positions()); },
          "(N, 3) the nodes' rest positions (m)")
      .def_property_readonly(
          "tets", [](const Scene& s) { return index_array(s.mesh.tets()); }, "(T, 4) each tetrahedron's nodes")
      .def_property_readonly(
          "surface", [](const Scene& s) { return index_array(s.mesh.surface()); },
          "(F, 3) the boundary triangles' nodes, outward")
      .def_property_readonly(
          "zones",
          [](const Scene& s) {
            py::dict d;
            for (const auto& [name, tets] : s.zones)
              d[py::str(name)] = py::array_t<int>(static_cast<py::ssize_t>(tets.size()), tets.data());
            return d;
          },
          "Each zone's name and its sorted tetrahedron indices (the constraints' order)")
      .def_property_readonly(
          "frame_times", [](const Scene& s) { return vector_array(s.frames.times()); },
          "The times (s) at which a run writes its frames")
      .def_property_readonly(
          "gravity", [](const Scene& s) { return std::vector<double>(s.gravity.data(), s.gravity.data() + 3); },
          "gravity: the acceleration vector (m/s^2)")
      .def_property_readonly(
          "integrator", [](const Scene& s) { return std::string(to_string(s.integrator.kind)); },
          "integrator.kind: ida, backward_euler, xpbd, ...")
      .def_property_readonly(
          "material", [](const Scene& s) { return std::string(to_string(s.material.model)); },
          "material.model: cnh, snh, unh, ...")
      .def_property_readonly(
          "notes", [](const Scene& s) { return s.notes; },
          "What to know about the scene as written (patches too coarse for the body, a locking lambda): one line "
          "each, as `isochor run` prints them")
      .def(
          "infsup",
          [](const Scene& s) {
            const InfSup r = zones_infsup(s);
            py::dict d;
            d["beta"] = r.beta;
            d["beta_next"] = r.beta_next;
            d["zero_modes"] = r.zero_modes;
            d["zones"] = r.zones;
            d["free_dofs"] = r.dofs;
            return d;
          },
          "The inf-sup constant of the scene's zones against its free dofs (`isochor infsup`): a dict of beta, "
          "beta_next, zero_modes, zones, free_dofs")
      .def("activations", &Scene::activations, py::arg("t"),
           "Each muscle's activation at time t as the scene gives it (activation_scale applied)")
      .def_property_readonly(
          "muscles",
          [](const Scene& s) {
            std::vector<std::string> names;
            for (const Scene::MuscleSpec& m : s.muscles) names.push_back(m.name);
            return names;
          },
          "The [[muscle]] names, in the order of activations()");
}

// The folder this module was loaded from (an installed package's isochor/, or build/python/isochor).
std::filesystem::path module_directory() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&module_directory), &info) == 0 || !info.dli_fname) return {};
  std::error_code ec;
  const std::filesystem::path file = std::filesystem::canonical(info.dli_fname, ec);
  return ec ? std::filesystem::path() : file.parent_path();
}

// The command line that studies run their cases with: the package's, else the build tree's.
const std::string& module_executable() {
  static const std::string exe = executable_beside(module_directory(), ISOCHOR_EXE).string();
  return exe;
}

}  // namespace

PYBIND11_MODULE(_isochor, m) {
  hdf5_no_cleanup_at_exit();  // no effect when h5py started HDF5 first
  m.doc() = "isochor's C++ core (use the isochor package)";
  bind_error(m);
  bind_scene(m);

  m.def(
      "load_scene",
      [](const std::string& path, py::object overrides) {
        return std::make_shared<Scene>(load_scene(path, overrides_of(overrides)));
      },
      py::arg("path"), py::arg("overrides") = py::none(), "A scene file with overrides (isochor.load)");
  m.def("scene_from_dict", &scene_from_dict, py::arg("scene"), py::arg("overrides") = py::none(),
        py::arg("name") = "<dict>", py::arg("directory") = "",
        "A scene from a dict shaped like the file (isochor.scene)");
  m.def("overrides", &overrides_of, py::arg("overrides"), "The `--set` strings of a dict or list of overrides");
  m.def("run", &run, py::arg("scene"), py::arg("output") = "", py::arg("mode") = "create", py::arg("progress") = false,
        py::arg("on_frame") = py::none(), py::arg("activation") = py::none(),
        "Runs a scene into its file; a dict of what it did (isochor.run)");

  m.def(
      "study_cases",
      [](const std::string& path, py::object overrides) {
        const Study s = load_study(path, overrides_of(overrides));
        py::list cases;
        for (const StudyCase& c : s.cases) {
          py::dict d;
          d["method"] = c.method;
          d["label"] = c.label;
          d["overrides"] = c.overrides;
          py::dict sweep;
          for (const auto& [k, v] : c.sweep) sweep[py::str(k)] = v;
          d["sweep"] = sweep;
          cases.append(d);
        }
        return py::make_tuple(s.output.string(), cases);
      },
      py::arg("path"), py::arg("overrides") = py::none(),
      "A study's output folder and its cases (isochor.study_cases)");
  m.def(
      "run_study",
      [](const std::string& path, py::object overrides, bool resume, bool progress) {
        const Study s = load_study(path, overrides_of(overrides));
        int failed = 0;
        {
          py::gil_scoped_release nogil;
          failed = run_study(s, module_executable(), resume, progress);
        }
        return py::make_tuple(s.output.string(), failed);
      },
      py::arg("path"), py::arg("overrides") = py::none(), py::arg("resume") = false, py::arg("progress") = false,
      "Runs a study's cases; its output folder and the count that failed (isochor.study)");
  m.attr("executable") = module_executable();
  m.attr("tools_dir") = tools_directory(module_directory(), ISOCHOR_TOOLS_DIR).string();
}
