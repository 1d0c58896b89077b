// The keys of a study file (`isochor study`), each declared once: the parser reads their defaults
// and ranges from here, and the key table of docs/studies.md is generated from here (`make docs`).
#include "isochor/app/study.hpp"

#include <iterator>

namespace isochor {

namespace {

using K = KeyKind;

constexpr KeySpec kRows[] = {
    {.name = "study", .kind = K::table, .doc = "`[study]`: the base scene and what every case shares"},
    {.name = "study.scene", .kind = K::string, .doc = "the base scene, relative to the study file"},
    {.name = "study.output",
     .kind = K::string,
     .shown = "`out/studies/<stem>`",
     .doc = "results directory (relative to the working directory)"},
    {.name = "study.jobs", .kind = K::integer, .fallback = "2", .min = 1, .max = 64, .doc = "cases run at once"},
    {.name = "study.kind",
     .kind = K::string,
     .fallback = "\"work_precision\"",
     .choices = "work_precision stability convergence",
     .doc = "`\"work_precision\"`, `\"stability\"` (a label for the report) or `\"convergence\"` (the reference is the "
            "base scene as it is unless `reference.set` says otherwise: meshes are compared with each other and with "
            "`observable.reference`, not with one run)"},
    {.name = "study.set",
     .kind = K::strings,
     .shown = "[]",
     .doc = "overrides applied to every case, `\"key=value\"` as for `--set`"},
    {.name = "reference", .kind = K::table, .doc = "`[reference]`: the case every other is measured against"},
    {.name = "reference.set",
     .kind = K::strings,
     .shown = "IDA, rtol 1e-10, atol 1e-12",
     .doc = "the reference case's overrides (after `study.set`)"},
    {.name = "method", .kind = K::tables, .doc = "`[[method]]`: one method"},
    {.name = "method.name", .kind = K::string, .doc = "its name (no `/`, space or `,`; not `reference`)"},
    {.name = "method.set", .kind = K::strings, .shown = "[]", .doc = "its overrides (after `study.set`)"},
    {.name = "method.sweep",
     .kind = K::table,
     .shown = "{}",
     .doc = "`{ \"key\" = [values], ... }`: one case per combination of the values (cartesian product)"},
    {.name = "method.sweep.<key>",
     .kind = K::numbers,
     .doc = "the values of a scene key (dotted, quoted: `\"integrator.rtol\" = [1e-4, 1e-6]`), one case each"},
    {.name = "method.scene",
     .kind = K::string,
     .shown = "`study.scene`",
     .doc =
         "this method's own base scene (relative to the study): one map for several bodies (`studies/robustness.toml`: "
         "a cube and a jelly); its errors against the reference are left blank when its mesh is not the reference's"},
    {.name = "observable",
     .kind = K::table,
     .doc = "`[observable]`: one number measured on every case (`tools/study_report.py`), for convergence studies"},
    {.name = "observable.name",
     .kind = K::string,
     .fallback = "\"observable\"",
     .doc = "its label in the report and chart"},
    {.name = "observable.kind",
     .kind = K::string,
     .choices = "point set",
     .doc = "`\"point\"`: the displacement of the node nearest `point` at rest; `\"set\"`: the mean displacement of "
            "the mesh's node set `set`"},
    {.name = "observable.point", .kind = K::vec3, .doc = "point: a rest position (m)"},
    {.name = "observable.set",
     .kind = K::string,
     .doc = "set: a node set of the mesh (Gmsh physical group, `xmax`, ...)"},
    {.name = "observable.component",
     .kind = K::string,
     .fallback = "\"norm\"",
     .choices = "x y z norm",
     .doc = "`\"x\"`, `\"y\"`, `\"z\"` or `\"norm\"` of that displacement"},
    {.name = "observable.frame",
     .kind = K::integer,
     .fallback = "-1",
     .min = -1000000,
     .max = 1000000,
     .doc = "the frame (negative: from the end)"},
    {.name = "observable.reference",
     .kind = K::number,
     .doc = "the known value (a textbook's): errors and orders against it; without it, each mesh against the next "
            "finer one and Richardson's order from three meshes"},
};

}  // namespace

const KeyTable& study_keys() {
  static const KeyTable table("apps/src/study_keys.cpp", {std::begin(kRows), std::end(kRows)});
  return table;
}

}  // namespace isochor
