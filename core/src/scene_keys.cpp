// The keys of a scene file, each declared once: the parsers read their defaults and ranges from
// here, and the key tables of docs/scenes.md are generated from here (`make docs`). A row's
// `fallback` is the default the parser uses; `shown` is what the docs say where the default
// depends on other keys or needs a word ("0 (off)"). The order is the docs' order.
#include "isochor/core/key_table.hpp"

#include <iterator>
#include <limits>

namespace isochor {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using K = KeyKind;

constexpr KeySpec kRows[] = {
    {.name = "mesh", .kind = K::table, .doc = "the body: a shape or a mesh file"},
    {.name = "mesh.shape",
     .kind = K::string,
     .choices = "box capsule cylinder sphere two_tets",
     .doc = "`\"box\"`, `\"capsule\"`, `\"cylinder\"`, `\"sphere\"` or `\"two_tets\"`"},
    {.name = "mesh.file",
     .kind = K::string,
     .doc =
         "a mesh file: Gmsh `.msh` (v2 or v4), a Gmsh `.geo` script (its volumes meshed by Gmsh, at the script's sizes "
         "or `edge_length`; physical groups as for `.msh`: textbook shapes such as Cook's membrane in one file, "
         "`demos/meshes/cook.geo`), TetGen `.node`/`.ele`, or a closed surface `.obj`/`.stl` tetrahedralised by Gmsh"},
    {.name = "mesh.parameters", .kind = K::table, .doc = "`.geo` only: numbers the script reads (below)"},
    {.name = "mesh.parameters.<name>",
     .kind = K::number,
     .range = {-1000000000000000.0, 1000000000000000.0, false, false},
     .doc = "`.geo` only: a number the script reads, defined before it runs, so that it replaces the script's "
            "`DefineConstant[<name> = ...]` (`demos/meshes/cook.geo`: `mesh.parameters.N = 64` makes the panel 64 "
            "elements along an edge and one layer of elements thick, the textbook plane-strain mesh; `edge_length` "
            "alone keeps its thickness of 6 and fills it with layers). A name is letters, digits and `_`"},
    {.name = "mesh.center",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .range = Range::coordinate(),
     .doc = "centre of a shape (box, cylinder, sphere)"},
    {.name = "mesh.inner_radius",
     .kind = K::number,
     .unit = "m",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "sphere: a hollow sphere (a thick-walled shell) with this inner radius; its wall's nodes in the node sets "
            "`inner` and `outer`"},
    {.name = "mesh.size",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[1, 1, 1]",
     .range = Range::length(),
     .doc = "box: edge lengths"},
    {.name = "mesh.cells", .kind = K::int3, .fallback = "4", .min = 1, .max = 1000, .doc = "box: cells per axis"},
    {.name = "mesh.split",
     .kind = K::integer,
     .fallback = "6",
     .min = 5,
     .max = 6,
     .doc = "box: tets per hex cell, 5 (alternating) or 6 (Kuhn)"},
    {.name = "mesh.sliver_ratio",
     .kind = K::number,
     .fallback = "1",
     .range = {1.0, 1000000.0, false, false},
     .doc = "box: a deliberately bad mesh for robustness tests (`demos/scramble.toml`): along each axis the cell "
            "layers alternate thick and thin, the thin ones this many times thinner (the size kept). With the Kuhn "
            "split the smallest face angle is atan(1/(√2 r)) (0.68° at r = 60) and the largest edge ratio √(2r² + 1) "
            "(85 at r = 60); `tools/mesh_quality.py` prints the histograms"},
    {.name = "mesh.radius",
     .kind = K::number,
     .unit = "m",
     .shown = "0.5 (capsule, cylinder), 1 (sphere)",
     .range = Range::positive(),
     .doc = "capsule, cylinder or sphere radius"},
    {.name = "mesh.from",
     .kind = K::vec3,
     .unit = "m",
     .doc = "capsule: one end of its axis (the centre of one hemispherical cap)"},
    {.name = "mesh.to", .kind = K::vec3, .unit = "m", .doc = "capsule: the other end"},
    {.name = "mesh.height",
     .kind = K::number,
     .unit = "m",
     .fallback = "1",
     .range = Range::positive(),
     .doc = "cylinder height, along z"},
    {.name = "mesh.resolution",
     .kind = K::integer,
     .fallback = "24",
     .min = 6,
     .max = 10000,
     .doc = "cylinder: element edges around the circumference, 6..10000 (edge length 2πr/resolution)"},
    {.name = "mesh.target_tets",
     .kind = K::integer,
     .fallback = "5000",
     .min = 10,
     .max = 100000000,
     .doc = "sphere: approximate number of tets (met within a few %)"},
    {.name = "mesh.edge_length",
     .kind = K::number,
     .unit = "m",
     .shown = "0 (off); capsule: radius/3",
     .range = Range::non_negative(),
     .doc = "sphere: element edge length instead of `target_tets`; capsule: element edge length; surface file: "
            "interior edge length (0 follows the surface); `.geo`: the size everywhere (0: the script's own)"},
    {.name = "mesh.edge",
     .kind = K::number,
     .unit = "m",
     .fallback = "1",
     .range = Range::positive(),
     .doc = "two_tets: edge of the shared equilateral face"},
    {.name = "material", .kind = K::table, .doc = "the material of the body"},
    {.name = "material.model",
     .kind = K::string,
     .fallback = "\"cnh\"",
     .choices = "cnh unh snh snh_simple mass_spring",
     .doc = "`\"cnh\"` (constrained neo-Hookean), `\"unh\"` (Bonet–Wood neo-Hookean), `\"snh\"` (stable neo-Hookean, "
            "Smith et al. 2018 with its log term, run with their re-parametrisation μ' = 4/3 μ, λ' = λ + 5/6 μ: its "
            "small-strain shear modulus is μ, as neo-Hooke's, but its isochoric part μ'/2 (I_C − 3) − μ'/2 log(I_C + "
            "1) makes it stiffer at large stretch: in incompressible uniaxial tension its nominal stress is (4/3) I/(I "
            "+ 1) times neo-Hooke's, I = λ² + 2/λ: +0.9% at stretch 1.2, +4.2% at 1.5, +11% at 2; `isochor run` says "
            "so), `\"snh_simple\"` (μ/2 (I_C − 3) + λ'/2 (J − α)², λ' = λ + μ, α = 1 + μ/λ': the common stable "
            "neo-Hookean test form, also the energy of the XPBD constraint pair), `\"mass_spring\"` (Hong et al. 2006: "
            "only the surface nodes move, joined by structural, shear and bending springs; one constraint keeps the "
            "volume the surface encloses; interior nodes are carried for output; runs on IDA, backward Euler or its "
            "own step `integrator.kind = \"mass_spring\"`; no zones)"},
    {.name = "material.density",
     .kind = K::number,
     .unit = "kg/m³",
     .fallback = "1000",
     .range = Range::density(),
     .doc = "mass density"},
    {.name = "material.mu",
     .kind = K::number,
     .unit = "Pa",
     .fallback = "1e4",
     .range = Range::modulus(),
     .doc = "shear modulus (Lamé μ)"},
    {.name = "material.lambda",
     .kind = K::number,
     .unit = "Pa",
     .fallback = "9e4",
     .range = Range::modulus_or_zero(),
     .doc =
         "Lamé λ; for CNH the weight of the local compression penalty: where zones finer than the global one keep the "
         "volume, about μ suffices, and more stiffens the body as a nearly incompressible UNH locks (Cook's membrane "
         "with 2-ring patches, h = 3: +0.8% at μ, −4% at 10 μ, −47% at 5,000 μ); above 10 μ `isochor run` says so. The "
         "same holds for UNH and SNH given zones: with 2-ring patches (`zones.patches = 2`) and λ = μ they do not lock "
         "(Cook's membrane at h = 3: 6.916 and 6.917 against 6.93, where UNH with ν = 0.4999 and no zones gives 3.65)"},
    {.name = "material.E",
     .kind = K::number,
     .unit = "Pa",
     .fallback = "1e5",
     .range = Range::modulus(),
     .doc = "Young's modulus (with `nu`)"},
    {.name = "material.nu",
     .kind = K::number,
     .fallback = "0.45",
     .range = {-1.0, 0.5, true, false},
     .doc = "Poisson's ratio (with `E`); 0.5 (λ = ∞, a hard hydrostatic constraint) only with `integrator.kind = "
            "\"xpbd\"`"},
    {.name = "material.beta",
     .kind = K::number,
     .fallback = "1",
     .range = Range::non_negative(),
     .doc = "CNH penalty shape β in U(J;β) = (J−1)²[β(J−1)² + 6]/12"},
    {.name = "material.epsilon",
     .kind = K::number,
     .fallback = "0.1",
     .range = {0.0, 1.0, true, false},
     .doc = "CNH: J below which α̃ = J^(−1/3) is continued by its C² quadratic"},
    {.name = "material.epidermis_lambda",
     .kind = K::number,
     .unit = "N/m",
     .fallback = "0",
     .shown = "0 (off)",
     .range = Range::non_negative(),
     .doc = "epidermis λ_e: A₀ λ_e U(J̃; γ) on every surface triangle (CNH paper eq. 16)"},
    {.name = "material.epidermis_gamma",
     .kind = K::number,
     .fallback = "1",
     .range = Range::non_negative(),
     .doc = "epidermis γ"},
    {.name = "material.spring_stiffness",
     .kind = K::number,
     .unit = "N/m",
     .fallback = "1000",
     .range = Range::positive(),
     .doc = "mass_spring: stiffness of every structural, shear and bending spring (read for every model, used by "
            "mass_spring)"},
    {.name = "material.spring_damping",
     .kind = K::number,
     .unit = "N s/m",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "mass_spring: dashpot along every spring"},
    {.name = "material.volume_constraint",
     .kind = K::boolean,
     .fallback = "true",
     .doc = "mass_spring: keep the volume enclosed by the surface (false: the conventional mass-spring model)"},
    {.name = "material.region",
     .kind = K::tables,
     .doc = "`[[material.region]]`: tets with their own elastic constants and density (fat, muscle and tendon in one "
            "body), the body's `model` and other keys; a tet in several regions takes the last one's. IDA, backward "
            "Euler and statics (not XPBD or the mass-spring model)"},
    {.name = "material.region.zone",
     .kind = K::string,
     .doc = "its tets: a zone of `[zones]` by name; excludes `select`"},
    {.name = "material.region.select",
     .kind = K::table,
     .like = "select",
     .doc = "its tets: a selection (see Selections); excludes `zone`"},
    {.name = "material.region.mu",
     .kind = K::number,
     .unit = "Pa",
     .shown = "the body's",
     .range = Range::modulus(),
     .doc = "the region's shear modulus (with `lambda`; or `E` and `nu`, not both pairs)"},
    {.name = "material.region.lambda",
     .kind = K::number,
     .unit = "Pa",
     .shown = "the body's",
     .range = Range::modulus_or_zero(),
     .doc = "the region's first Lamé parameter"},
    {.name = "material.region.E",
     .kind = K::number,
     .unit = "Pa",
     .range = Range::modulus(),
     .doc = "the region's Young's modulus"},
    {.name = "material.region.nu",
     .kind = K::number,
     .range = {-1.0, 0.5, true, false},
     .doc = "the region's Poisson's ratio"},
    {.name = "material.region.density",
     .kind = K::number,
     .unit = "kg/m³",
     .shown = "the body's",
     .range = Range::density(),
     .doc = "the region's density (its tets' share of the lumped masses)"},
    {.name = "zones", .kind = K::table, .doc = "volume-preserving zones"},
    {.name = "zones.global",
     .kind = K::boolean,
     .shown = "cnh: true when the table names other zones but no patches, or with `default = \"global\"`; else false "
              "(the default is 2-ring patches); false for the other models",
     .doc = "one zone, `global`, holding every tet. Together with zones that partition the mesh (`zones.patches`, or "
            "mesh regions that cover it) its volume is their sum at every shape. Any zone whose tets are sums and "
            "differences of other zones' tets (this one; one per colour class of 1-ring zones on a mesh whose nodes "
            "four-colour, as the boxes' six tets per cube do) is found before the run (exact elimination of the zones' "
            "tet sets) and gets no constraint row: the others' rows keep its volume exactly, every solver (`klu` "
            "included) runs it, and its volume is written like any zone's; the run's first line names the zones "
            "(`/frames/multipliers` has one column fewer for each)"},
    {.name = "zones.default",
     .kind = K::string,
     .fallback = "\"patches\"",
     .choices = "patches global",
     .doc = "what a CNH body gets when the table names no zone (none of `global`, `rings`, `patches`, `from_mesh`, "
            "`paint`, `zone`): `\"patches\"` (2-ring patches, see `zones.patches`) or `\"global\"` (the CNH paper's "
            "one zone over the whole body, as its scenes in `demos/` use). UNH and SNH get no zones unless the table "
            "names them, so a scene switched to them by `--set material.model=unh` runs unconstrained"},
    {.name = "zones.rings",
     .kind = K::integer,
     .fallback = "0",
     .shown = "0 (off)",
     .min = 0,
     .max = 100,
     .doc = "one zone per node, `ring<k>_<node>`: the tets of its k-ring (k = 1: Irving et al. 2007's 1-ring zones); "
            "nodes whose rings hold the same tets share one zone"},
    {.name = "zones.patches",
     .kind = K::integer,
     .shown = "cnh with no zone named in `[zones]`: 2; otherwise 0 (off)",
     .min = 0,
     .max = 100,
     .doc = "a partition into patches about the size of a k-ring, `patch<k>_<i>`: seed nodes at least 2k edges apart, "
            "every node to its nearest seed, each tet to the patch of its lowest-numbered node; patches do not "
            "overlap. The default: 2-ring patches are the smallest whose inf-sup constant stays bounded as the mesh is "
            "refined (0.64–0.78 on Cook's membrane and a clamped cube, against 1-ring patches falling from 0.43 to "
            "0.11 and per-node 1-ring zones near 0.1: `isochor infsup`, [results](results/infsup/report.md)), so they "
            "neither lock nor, as the global zone alone does, leave local changes of volume to the penalty; a mesh "
            "with fewer than two patches across a principal direction of the body gets a note (`isochor run`, `isochor "
            "mesh`) saying how many there are. Patches whose tets have every node driven (by `[[boundary]]` or bones) "
            "are left out: no free node moves their volume"},
    {.name = "zones.from_mesh",
     .kind = K::boolean,
     .fallback = "false",
     .doc = "add the zones of the mesh file (Gmsh 3-D physical groups, TetGen regions)"},
    {.name = "zones.restore_time",
     .kind = K::number,
     .unit = "s",
     .fallback = "0",
     .shown = "0 (off)",
     .range = Range::non_negative(),
     .doc = "a start whose zone volumes are not the rest volumes (`initial.flatten`) cannot hold g = 0: each zone's "
            "target volume then goes from its volume at the start to its rest volume over this time, along the C² "
            "quintic 10s³ − 15s⁴ + 6s⁵ (no jump in the target's rate or acceleration), a breakpoint for IDA at its "
            "end; the constraints are exact along the way. Volume errors in `/frames/volume` stay measured against the "
            "rest volume"},
    {.name = "zones.keep",
     .kind = K::boolean,
     .fallback = "true",
     .doc = "false: the zones' volumes are measured and written, not constrained (compare an unconstrained model on "
            "the same zones)"},
    {.name = "zones.paint",
     .kind = K::tables,
     .doc = "`[[zones.paint]]`: zones painted on the surface (the CNH paper's §6), one per entry of `labels`, `colors` "
            "or `weights` (exactly one of them). Each surface node takes the paint of the nearest painted vertex; each "
            "tet the paint at the surface point nearest to its centroid (where the gradient of the distance to the "
            "surface leads), interpolated on that point's triangle, and it is in every zone painted there at least ½. "
            "Zones may overlap (several `[[zones.paint]]`, or weights); `zones.global` adds the whole body on top"},
    {.name = "zones.paint.file",
     .kind = K::string,
     .doc = "the paint, relative to the scene file: `.ply` (the vertex element's x, y, z and any scalar property, "
            "ASCII or binary, as painting tools export; uchar colours scaled to 0..1), `.obj` (`v x y z r g b`, "
            "colours 0..1), or `.csv` with a header row: `x,y,z,<properties>` (points) or `node,<properties>` (mesh "
            "node indices, as in `/mesh/rest_positions`)"},
    {.name = "zones.paint.groups",
     .kind = K::strings,
     .doc = "instead of a file: surface groups of the mesh file (Gmsh 2-D physical groups; any of the mesh's node "
            "sets), each a zone of its name with paint 1 on the group's nodes and 0 elsewhere on the surface, carried "
            "into the volume as above"},
    {.name = "zones.paint.labels",
     .kind = K::table,
     .doc = "zone name → integer label, e.g. `{ belly = 1, back = 2 }`: the vertices whose `property` equals it"},
    {.name = "zones.paint.labels.<zone>",
     .kind = K::integer,
     .min = -2147483647,
     .max = 2147483647,
     .doc = "the label painted for zone `<zone>`"},
    {.name = "zones.paint.property",
     .kind = K::string,
     .fallback = "\"label\"",
     .doc = "labels: the vertex property (PLY) or column (CSV) holding them"},
    {.name = "zones.paint.colors",
     .kind = K::table,
     .doc = "zone name → colour `[r, g, b]` (0..1, or 0..255 when a component exceeds 1): the vertices whose colour is "
            "within `color_tolerance` of it (the nearest listed colour)"},
    {.name = "zones.paint.colors.<zone>",
     .kind = K::numbers,
     .range = Range::non_negative(),
     .type = "[r, g, b]",
     .doc = "the colour painted for zone `<zone>`"},
    {.name = "zones.paint.color_tolerance",
     .kind = K::number,
     .fallback = "0.1",
     .range = Range::positive(),
     .doc = "colors: the largest RGB distance (0..1 units) that counts as the colour"},
    {.name = "zones.paint.weights",
     .kind = K::table,
     .doc = "zone name → a vertex property (PLY) or column (CSV) holding a weight: painted where the interpolated "
            "weight is at least ½"},
    {.name = "zones.paint.weights.<zone>", .kind = K::string, .doc = "the property holding zone `<zone>`'s weight"},
    {.name = "zones.paint.tolerance",
     .kind = K::number,
     .unit = "m",
     .shown = "2% of the mesh's bounding-box diagonal",
     .range = Range::positive(),
     .doc =
         "a surface node farther than this from every painted vertex stops the run: the paint is of another surface"},
    {.name = "zones.paint.disconnected",
     .kind = K::string,
     .fallback = "\"error\"",
     .choices = "error keep split",
     .doc = "a zone painted in pieces that share no node: `\"error\"` (names the zone and the pieces' sizes), "
            "`\"keep\"` (one zone), `\"split\"` (zones `<name>_1`, `<name>_2`, … largest first)"},
    {.name = "zones.zone", .kind = K::tables, .doc = "`[[zones.zone]]`: a named zone"},
    {.name = "zones.zone.name", .kind = K::string, .doc = "zone name (no `/`, `.` or `,`)"},
    {.name = "zones.zone.select", .kind = K::table, .like = "select", .doc = "which tets: a selection (below)"},
    {.name = "select",
     .kind = K::table,
     .doc = "the keys below belong to every key whose type is selection (`zones.zone.select`, `boundary.select`, "
            "`muscle.origin`, ...), written `select.kind` here"},
    {.name = "select.kind",
     .kind = K::string,
     .choices = "all box half_space cylinder surface indices k_ring set",
     .doc = "`\"all\"`, `\"box\"`, `\"half_space\"`, `\"cylinder\"`, `\"surface\"`, `\"indices\"`, `\"k_ring\"`, "
            "`\"set\"`"},
    {.name = "select.min", .kind = K::vec3, .unit = "m", .doc = "box: lower corner"},
    {.name = "select.max", .kind = K::vec3, .unit = "m", .doc = "box: upper corner"},
    {.name = "select.point",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .range = Range::coordinate(),
     .doc = "half_space: a point on the plane"},
    {.name = "select.normal", .kind = K::vec3, .doc = "half_space: keeps (x − point)·normal ≥ 0"},
    {.name = "select.center",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .range = Range::coordinate(),
     .doc = "cylinder: a point on the axis (the middle when `length` is set)"},
    {.name = "select.axis", .kind = K::vec3, .fallback = "[0, 0, 1]", .doc = "cylinder: axis direction"},
    {.name = "select.radius",
     .kind = K::number,
     .unit = "m",
     .range = Range::positive(),
     .doc = "cylinder: keeps points within this distance of the axis"},
    {.name = "select.length",
     .kind = K::number,
     .unit = "m",
     .shown = "unbounded",
     .range = Range::non_negative(),
     .doc = "cylinder: and within length/2 of `center` along the axis (0: a disc in the plane through `center`)"},
    {.name = "select.indices",
     .kind = K::integers,
     .min = 0,
     .max = 2147483647,
     .doc = "indices: node or tet indices (0-based)"},
    {.name = "select.node", .kind = K::integer, .min = 0, .max = 2147483647, .doc = "k_ring: the centre node"},
    {.name = "select.k",
     .kind = K::integer,
     .fallback = "1",
     .min = 1,
     .max = 1000,
     .doc = "k_ring: nodes within k edges; tets touching the (k−1)-ring (k = 1: the tets around the node)"},
    {.name = "select.name", .kind = K::string, .doc = "set: a node set or zone of the mesh"},
    {.name = "boundary", .kind = K::tables, .doc = "`[[boundary]]`: one Dirichlet condition"},
    {.name = "boundary.select",
     .kind = K::table,
     .like = "select",
     .doc = "which nodes: a selection (see Selections; `kind`, `min`, `max`, `name`, ... as for zones)"},
    {.name = "boundary.kind",
     .kind = K::string,
     .fallback = "\"fixed\"",
     .choices = "fixed ramp keyframes sinusoid rotation",
     .doc = "`\"fixed\"`, `\"ramp\"`, `\"keyframes\"`, `\"sinusoid\"`, `\"rotation\"`"},
    {.name = "boundary.displacement", .kind = K::vec3, .unit = "m", .doc = "ramp: displacement reached at `t1`"},
    {.name = "boundary.t0",
     .kind = K::number,
     .unit = "s",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "ramp: start"},
    {.name = "boundary.t1",
     .kind = K::number,
     .unit = "s",
     .fallback = "1",
     .range = Range::positive(),
     .doc = "ramp: end (u constant after)"},
    {.name = "boundary.amplitude",
     .kind = K::vec3,
     .unit = "m",
     .doc = "sinusoid: u = amplitude · sin(2π f t + phase)"},
    {.name = "boundary.frequency",
     .kind = K::number,
     .unit = "Hz",
     .fallback = "1",
     .range = Range::positive(),
     .doc = "sinusoid"},
    {.name = "boundary.phase", .kind = K::number, .unit = "rad", .fallback = "0", .doc = "sinusoid"},
    {.name = "boundary.times",
     .kind = K::numbers,
     .unit = "s",
     .doc = "keyframes and rotation: increasing times (at least 2)"},
    {.name = "boundary.values",
     .kind = K::numbers,
     .unit = "m",
     .doc = "keyframes: 3 numbers (a displacement) per time, flattened"},
    {.name = "boundary.interpolation",
     .kind = K::string,
     .fallback = "\"linear\"",
     .choices = "linear cubic",
     .doc = "keyframes and rotation: `\"linear\"` or `\"cubic\"` (Catmull-Rom Hermite with zero tangents at the first "
            "and last keys: C¹ everywhere, also where the value starts and stops being held)"},
    {.name = "boundary.angles", .kind = K::numbers, .unit = "degrees", .doc = "rotation: the angle at each of `times`"},
    {.name = "boundary.axis",
     .kind = K::vec3,
     .fallback = "[0, 0, 1]",
     .doc = "rotation: axis direction (right-handed)"},
    {.name = "boundary.center",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .range = Range::coordinate(),
     .doc = "rotation: a point on the axis"},
    {.name = "boundary.components",
     .kind = K::strings,
     .shown = "all three",
     .doc = "hold only these components (any of `\"x\"`, `\"y\"`, `\"z\"`): a roller, or a face pulled along one axis "
            "while it contracts sideways. The nodes stay unknowns, with one constraint row per held component, g = d · "
            "(x − X − u(t)) = 0 (u the driver's displacement, acting on the held components only); the row's "
            "multiplier is the support's reaction (the force on the node is −λ d, N). Supports that hold some "
            "components may share nodes (a corner on two symmetry planes) if their directions are independent. IDA, "
            "backward Euler and statics; XPBD projects the held components exactly after every sweep (the nearest "
            "point satisfying all of a node's held directions); the mass-spring model's step solves them with its "
            "volume row (surface nodes only: its interior is carried). Not with `kind = \"rotation\"`"},
    {.name = "boundary.normal",
     .kind = K::vec3,
     .doc = "hold only the component along this direction (a symmetry plane or a skewed roller: the nodes slide in the "
            "plane normal to it); excludes `components`"},
    {.name = "skeleton", .kind = K::table, .doc = "bones that drive the tissue"},
    {.name = "skeleton.bvh",
     .kind = K::string,
     .doc = "a BVH motion-capture file (relative to the scene file) for bones with `motion = \"bvh\"`"},
    {.name = "skeleton.bone", .kind = K::tables, .doc = "`[[skeleton.bone]]`: the bones, parents before children"},
    {.name = "skeleton.bone.name", .kind = K::string, .doc = "bone name (unique, not `ground`)"},
    {.name = "skeleton.bone.parent",
     .kind = K::string,
     .fallback = "\"ground\"",
     .doc = "the bone it hangs from: `\"ground\"` or a bone defined above"},
    {.name = "skeleton.bone.joint",
     .kind = K::string,
     .fallback = "\"weld\"",
     .choices = "weld pin universal ball",
     .doc = "`\"weld\"`, `\"pin\"`, `\"universal\"` or `\"ball\"`"},
    {.name = "skeleton.bone.origin",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .doc = "the joint: where the bone meets its parent (rest pose)"},
    {.name = "skeleton.bone.direction",
     .kind = K::vec3,
     .fallback = "[1, 0, 0]",
     .doc = "along the bone (its capsule's axis)"},
    {.name = "skeleton.bone.length",
     .kind = K::number,
     .unit = "m",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "capsule: the axis segment ends at origin + length · direction"},
    {.name = "skeleton.bone.start",
     .kind = K::number,
     .unit = "m",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "capsule: the axis segment starts at origin + start · direction (leaves the joint region free)"},
    {.name = "skeleton.bone.from",
     .kind = K::vec3,
     .unit = "m",
     .shown = "origin + start · direction",
     .doc = "capsule: start of the axis segment, given directly (instead of direction, start, length)"},
    {.name = "skeleton.bone.to",
     .kind = K::vec3,
     .unit = "m",
     .shown = "origin + length · direction",
     .doc = "capsule: end of the axis segment"},
    {.name = "skeleton.bone.radius",
     .kind = K::number,
     .unit = "m",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "capsule radius; 0 binds nothing by distance"},
    {.name = "skeleton.bone.attach_distance",
     .kind = K::number,
     .unit = "m",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "also bind nodes up to this distance outside the capsule"},
    {.name = "skeleton.bone.select",
     .kind = K::table,
     .like = "select",
     .doc = "bind exactly these nodes (a selection, as `zones.zone.select`) instead of the capsule's"},
    {.name = "skeleton.bone.axis",
     .kind = K::vec3,
     .shown = "[0, 0, 1] (pin), [1, 0, 0] (universal)",
     .doc = "pin: rotation axis; universal: first axis (right-handed)"},
    {.name = "skeleton.bone.axis2",
     .kind = K::vec3,
     .fallback = "[0, 1, 0]",
     .doc = "universal: second axis (made perpendicular to `axis`)"},
    {.name = "skeleton.bone.order",
     .kind = K::string,
     .fallback = "\"XYZ\"",
     .doc = "ball: the axes of its three angles, in order"},
    {.name = "skeleton.bone.motion",
     .kind = K::string,
     .fallback = "\"none\"",
     .choices = "none keyframes sinusoid bvh",
     .doc = "`\"none\"` (angles 0), `\"keyframes\"`, `\"sinusoid\"` or `\"bvh\"`"},
    {.name = "skeleton.bone.times",
     .kind = K::numbers,
     .unit = "s",
     .doc = "keyframes: increasing times (at least 2); the angles stay at their end values outside"},
    {.name = "skeleton.bone.angles",
     .kind = K::numbers,
     .unit = "degrees",
     .doc = "keyframes: 1 (pin), 2 (universal) or 3 (ball) angles per time, flattened"},
    {.name = "skeleton.bone.interpolation",
     .kind = K::string,
     .fallback = "\"linear\"",
     .choices = "linear cubic",
     .doc = "keyframes: `\"linear\"` or `\"cubic\"` (as `boundary.interpolation`: C¹, smooth bone velocities; IDA "
            "needs them)"},
    {.name = "skeleton.bone.amplitude",
     .kind = K::numbers,
     .unit = "degrees",
     .doc = "sinusoid: one amplitude per angle, a = amplitude · sin(2π f t + phase)"},
    {.name = "skeleton.bone.frequency",
     .kind = K::number,
     .unit = "Hz",
     .fallback = "1",
     .range = Range::positive(),
     .doc = "sinusoid"},
    {.name = "skeleton.bone.phase", .kind = K::number, .unit = "rad", .fallback = "0", .doc = "sinusoid"},
    {.name = "skeleton.bone.bvh_joint",
     .kind = K::string,
     .shown = "the bone's name",
     .doc = "bvh: the BVH joint whose three rotation channels (in the file's order, cubic between frames, unwrapped) "
            "drive this ball joint; position channels are not used"},
    {.name = "character", .kind = K::table, .doc = "a rigged glTF character"},
    {.name = "character.file", .kind = K::string, .doc = "the `.glb` or `.gltf` file (relative to the scene file)"},
    {.name = "character.clip",
     .kind = K::string,
     .fallback = "\"\"",
     .shown = "`\"\"` (rest pose)",
     .doc = "the animation by name or index (`\"0\"`); an unknown name lists the file's clips"},
    {.name = "character.edge_length",
     .kind = K::number,
     .unit = "m",
     .shown = "the render mesh's largest extent / 25",
     .range = Range::positive(),
     .doc = "the tets' size"},
    {.name = "character.wrap_alpha",
     .kind = K::number,
     .unit = "m",
     .shown = "`edge_length`",
     .range = Range::positive(),
     .doc = "the alpha wrap's ball radius: gaps narrower than about twice it are closed"},
    {.name = "character.wrap_offset",
     .kind = K::number,
     .unit = "m",
     .shown = "`wrap_alpha` / 20",
     .range = Range::positive(),
     .doc = "how far outside the render mesh the wrap lies"},
    {.name = "character.bone_radius",
     .kind = K::number,
     .fallback = "0.5",
     .range = {0.0, 1.0, false, false},
     .doc = "a bone's capsule radius as a fraction of the skin's thickness about it; 0 binds nothing"},
    {.name = "character.joint_gap",
     .kind = K::number,
     .fallback = "1",
     .range = Range::non_negative(),
     .doc = "the clearance between a capsule and a joint that turns by a right angle, in capsule radii (less for "
            "smaller turns)"},
    {.name = "character.bvh",
     .kind = K::string,
     .doc = "a BVH file (relative to the scene file) that drives the joints instead of a clip"},
    {.name = "character.bvh_scale",
     .kind = K::number,
     .unit = "m",
     .fallback = "1",
     .range = Range::positive(),
     .doc = "the BVH file's length unit in metres (Mixamo's centimetres: 0.01)"},
    {.name = "character.bvh_joints",
     .kind = K::table,
     .shown = "the joints' own names",
     .doc = "which BVH joint drives each joint of the character"},
    {.name = "character.bvh_joints.<joint>",
     .kind = K::string,
     .doc = "the BVH joint that drives `<joint>` (joints not listed turn with their parents)"},
    {.name = "character.blend_in",
     .kind = K::number,
     .unit = "s",
     .fallback = "0.5",
     .range = Range::non_negative(),
     .doc = "from the rest pose to the clip's first pose, then the clip"},
    {.name = "character.loop",
     .kind = K::boolean,
     .fallback = "true",
     .doc = "repeat the clip to the run's end (false: hold its last pose)"},
    {.name = "character.regions",
     .kind = K::table,
     .shown = "one zone per joint",
     .doc = "a zone per key below, holding the tets whose dominant joint it lists"},
    {.name = "character.regions.<zone>",
     .kind = K::strings,
     .doc = "the joints of zone `<zone>` (each joint in one region at most)"},
    {.name = "load", .kind = K::tables, .doc = "`[[load]]`: one load"},
    {.name = "load.select",
     .kind = K::table,
     .like = "select",
     .doc = "which nodes (a selection, as for `[[boundary]]`); a traction acts on the surface triangles whose three "
            "corners are all selected"},
    {.name = "load.kind",
     .kind = K::string,
     .fallback = "\"point\"",
     .choices = "point traction pressure",
     .doc =
         "`\"point\"`: a force on the nodes; `\"traction\"`: a force per rest area on the surface, a third of each "
         "triangle's share to each corner (the consistent load of linear triangles); `\"pressure\"`: a follower load "
         "normal to the deformed surface, −p a/3 to each corner of a triangle of area vector a (outward), with its "
         "exact load stiffness (not symmetric on an open surface: exact with `linear_solver = \"klu\"`, the default of "
         "IDA and statics; the reduced and krylov solvers use it as if symmetric, which Newton absorbs at more "
         "iterations). Not an energy in general: left out of `/frames/energy`. Not with the mass-spring model"},
    {.name = "load.force", .kind = K::vec3, .unit = "N", .doc = "point: the force"},
    {.name = "load.split",
     .kind = K::boolean,
     .fallback = "true",
     .doc = "point: split the force equally among the selected nodes (false: the whole force on each)"},
    {.name = "load.traction",
     .kind = K::vec3,
     .unit = "N/m²",
     .doc = "traction: force per rest area (a nominal traction)"},
    {.name = "load.pressure",
     .kind = K::number,
     .unit = "Pa",
     .doc = "pressure: positive pushes into the body (on a cavity's wall: inflates it)"},
    {.name = "load.ramp",
     .kind = K::number,
     .unit = "s",
     .fallback = "0",
     .shown = "0 (full at once)",
     .range = Range::non_negative(),
     .doc = "the load grows linearly from 0 to full at this time (statics: pseudo-time; a breakpoint of IDA's steps)"},
    {.name = "load.times",
     .kind = K::numbers,
     .unit = "s",
     .doc = "keyframes of the load's factor (at least 2, increasing; excludes `ramp`): piecewise linear between them, "
            "held outside; each key is a breakpoint of IDA's steps"},
    {.name = "load.factors",
     .kind = K::numbers,
     .doc = "the factor at each of `times` (any sign: 1 is the load as given)"},
    {.name = "muscle", .kind = K::tables, .doc = "`[[muscle]]`: one muscle"},
    {.name = "muscle.name", .kind = K::string, .doc = "the muscle's name (no `/`, `.` or `,`; unique)"},
    {.name = "muscle.zone",
     .kind = K::string,
     .doc = "its tets: a zone of `[zones]` by name (painted, from the mesh, or `[[zones.zone]]`); excludes `select`"},
    {.name = "muscle.select",
     .kind = K::table,
     .like = "select",
     .doc = "its tets: a selection (see Selections); excludes `zone`"},
    {.name = "muscle.fibres",
     .kind = K::string,
     .fallback = "\"constant\"",
     .choices = "constant laplace file mesh",
     .doc = "`\"constant\"` (`direction`), `\"laplace\"` (from `origin` to `insertion`), `\"file\"` (`file`) or "
            "`\"mesh\"` (`field`)"},
    {.name = "muscle.direction",
     .kind = K::vec3,
     .doc = "constant: the fibre direction in the rest configuration (normalised)"},
    {.name = "muscle.origin",
     .kind = K::table,
     .like = "select",
     .doc = "laplace: a selection of nodes, where u = 0 (the muscle's nodes among them)"},
    {.name = "muscle.insertion",
     .kind = K::table,
     .like = "select",
     .doc =
         "laplace: a selection of nodes, where u = 1. u solves the Laplace equation on the muscle's tets (linear tets, "
         "a sparse Cholesky solve); each tet's fibre is ∇u/|∇u|, the usual fill of a fusiform muscle; a tet whose "
         "nodes all lie on the origin or the insertion takes the direction from the one's centroid to the other's"},
    {.name = "muscle.file",
     .kind = K::string,
     .doc = "file: a CSV file relative to the scene, header `tet,ax,ay,az`, one row per tet (mesh tet indices, as in "
            "`/mesh/tets`); every tet of the muscle must have a row, rows of other tets are ignored (one file may "
            "serve several muscles)"},
    {.name = "muscle.field",
     .kind = K::string,
     .fallback = "\"fibres\"",
     .doc = "mesh: the name of an element data view of the scene's `.msh` file (`$ElementData` with 3 components, "
            "as Gmsh writes a vector field on elements), one vector per tet, normalised; every tet of the muscle "
            "must have one"},
    {.name = "muscle.sigma_max",
     .kind = K::number,
     .unit = "Pa",
     .fallback = "3e5",
     .range = Range::non_negative(),
     .doc = "peak isometric stress at full activation (Blemker et al.: 300 kPa)"},
    {.name = "muscle.optimal_stretch",
     .kind = K::number,
     .fallback = "1",
     .range = {0.1, 10.0, false, false},
     .doc = "λ_ofl, the fibre stretch of peak active force (1: the rest length is optimal)"},
    {.name = "muscle.passive_k1",
     .kind = K::number,
     .unit = "Pa",
     .fallback = "0",
     .shown = "0 (off)",
     .range = Range::non_negative(),
     .doc = "passive fibre stiffness k₁ (tension only)"},
    {.name = "muscle.passive_k2",
     .kind = K::number,
     .fallback = "0",
     .range = {0.0, 100.0, false, false},
     .doc = "passive exponent k₂ (0: k₁(λ² − 1)²/2)"},
    {.name = "muscle.activation",
     .kind = K::number,
     .fallback = "0",
     .range = {0.0, 1.0, false, false},
     .doc = "a constant activation; excludes `activation_keys`, `activation_joint` and `activation_bvh`"},
    {.name = "muscle.activation_keys",
     .kind = K::table,
     .doc = "activation keyframes in time: `{ times = [..], values = [..], interpolation = \"linear\" }`"},
    {.name = "muscle.activation_keys.times",
     .kind = K::numbers,
     .unit = "s",
     .doc = "increasing times (at least 2); linear keys are breakpoints of IDA's steps"},
    {.name = "muscle.activation_keys.values",
     .kind = K::numbers,
     .doc = "the activation at each time, in [0, 1]; held outside the keys"},
    {.name = "muscle.activation_keys.interpolation",
     .kind = K::string,
     .fallback = "\"linear\"",
     .choices = "linear cubic",
     .doc = "`\"linear\"` or `\"cubic\"` (as `boundary.interpolation`)"},
    {.name = "muscle.activation_joint",
     .kind = K::table,
     .doc = "activation as a function of a skeleton joint's angle: `{ bone = \"forearm\", angles = [..], values = [..] "
            "}` (a flexor that fires as the elbow bends)"},
    {.name = "muscle.activation_joint.bone",
     .kind = K::string,
     .doc = "a bone of `[skeleton]` with a pin, universal or ball joint"},
    {.name = "muscle.activation_joint.axis",
     .kind = K::integer,
     .fallback = "0",
     .min = 0,
     .max = 2,
     .doc = "which of the joint's angles (0 for a pin)"},
    {.name = "muscle.activation_joint.angles",
     .kind = K::numbers,
     .unit = "degrees",
     .doc = "increasing joint angles (at least 2)"},
    {.name = "muscle.activation_joint.values",
     .kind = K::numbers,
     .doc = "the activation at each angle, in [0, 1]; held outside"},
    {.name = "muscle.activation_joint.interpolation",
     .kind = K::string,
     .fallback = "\"linear\"",
     .choices = "linear cubic",
     .doc = "`\"linear\"` or `\"cubic\"`"},
    {.name = "muscle.activation_bvh",
     .kind = K::table,
     .doc = "activation as a function of a BVH channel's value in time: `{ file = \"elbow_flex.bvh\", joint = "
            "\"Elbow\", channel = \"Xrotation\", channel_values = [..], values = [..] }` (a mocap clip's joint, "
            "whether or "
            "not it drives `[skeleton]`)"},
    {.name = "muscle.activation_bvh.file",
     .kind = K::string,
     .doc = "a BVH file, relative to the scene; its frames are at t = 0, frame time, 2 frame times, ..., the channel's "
            "value between frames the C¹ cubic through them (as a bone's `motion = \"bvh\"`), held after the last"},
    {.name = "muscle.activation_bvh.joint", .kind = K::string, .doc = "a joint of the file, by name"},
    {.name = "muscle.activation_bvh.channel",
     .kind = K::string,
     .choices = "Xposition Yposition Zposition Xrotation Yrotation Zrotation",
     .doc = "one of the joint's channels; a rotation is unwrapped across frames (no jump of 360°)"},
    {.name = "muscle.activation_bvh.channel_values",
     .kind = K::numbers,
     .doc = "increasing values of the channel (at least 2), in the file's units: degrees for a rotation"},
    {.name = "muscle.activation_bvh.values",
     .kind = K::numbers,
     .doc = "the activation at each channel value, in [0, 1]; held outside"},
    {.name = "muscle.activation_bvh.interpolation",
     .kind = K::string,
     .fallback = "\"linear\"",
     .choices = "linear cubic",
     .doc = "`\"linear\"` or `\"cubic\"`"},
    {.name = "muscles", .kind = K::table, .doc = "settings of every muscle"},
    {.name = "muscles.activation_scale",
     .kind = K::number,
     .fallback = "1",
     .range = {0.0, 1.0, false, false},
     .doc = "every muscle's activation times this (`--set muscles.activation_scale=0`: the same scene passive)"},
    {.name = "forces", .kind = K::table, .doc = "body forces"},
    {.name = "forces.gravity",
     .kind = K::vec3,
     .unit = "m/s²",
     .fallback = "[0, 0, -9.81]",
     .range = Range::acceleration(),
     .doc = "gravitational acceleration (each component within ±10⁷: a million g)"},
    {.name = "forces.gravity_ramp",
     .kind = K::number,
     .unit = "s",
     .fallback = "0",
     .shown = "0 (off)",
     .range = Range::non_negative(),
     .doc = "gravity grows linearly from 0 at t = 0 to full at this time (in statics, pseudo-time: 1 applies it in "
            "`frames.count` increments)"},
    {.name = "contact", .kind = K::table, .doc = "contact with planes and with itself"},
    {.name = "contact.ground", .kind = K::boolean, .fallback = "false", .doc = "a smooth ground plane"},
    {.name = "contact.point",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .range = Range::coordinate(),
     .doc = "a point on the ground plane"},
    {.name = "contact.normal",
     .kind = K::vec3,
     .fallback = "[0, 0, 1]",
     .doc = "the plane's normal, pointing to the free side"},
    {.name = "contact.stiffness",
     .kind = K::number,
     .unit = "N/m³",
     .fallback = "1e6",
     .range = Range::positive(),
     .doc = "k: energy k/3 (δ − s)³ per node whose distance s is below δ (C² in position)"},
    {.name = "contact.thickness",
     .kind = K::number,
     .unit = "m",
     .fallback = "1e-3",
     .range = Range::positive(),
     .doc = "δ: distance at which contact starts"},
    {.name = "contact.damping",
     .kind = K::number,
     .unit = "s/m",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "α: normal damping of the contact (Hunt & Crossley's form), force k α p² ṗ along the normal at penetration "
            "p = δ − s and penetration rate ṗ (relative to a moving plane), the elastic force k p² times α ṗ: smooth "
            "in position (C¹), linear in velocity, zero where contact starts. A point mass hitting at speed v₀ "
            "rebounds with restitution e = √(1 − 4/3 α v₀) to first order in α v₀ (so e falls with the impact speed, "
            "as measured restitutions do). Not with XPBD (its contact is a projection)"},
    {.name = "contact.law",
     .kind = K::string,
     .fallback = "\"node\"",
     .choices = "node area",
     .doc = "`\"node\"`: the energy above at every node, k in N/m³ (a finer mesh touches with more nodes: a stiffer "
            "ground). `\"area\"`: the same times the node's rest surface area (a third of its surface triangles'), k "
            "in N/m⁴: a pressure k p² at penetration p, the same ground at every resolution. The coarse ball's "
            "per-node k = 1e8 N/m³ is about k = 4.5e11 N/m⁴ per area (its mean surface-node area 2.2e-4 m²)"},
    {.name = "contact.friction",
     .kind = K::number,
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "μ_c: smoothed Coulomb friction, force −μ_c k p² u / √(|u|² + ε²) against the tangential velocity u "
            "relative to the collider (ε = `slip_speed`): the Coulomb force μ_c times the normal force k p² once "
            "sliding faster than ε, growing linearly below it. Not variational: with friction, backward Euler takes "
            "plain Newton steps (as `line_search = false`: its line search minimises a potential); not with XPBD. The "
            "default of every plane and collider"},
    {.name = "contact.slip_speed",
     .kind = K::number,
     .unit = "m/s",
     .fallback = "1e-3",
     .range = Range::positive(),
     .doc = "ε: the tangential speed below which friction grows linearly with the speed (smaller: closer to Coulomb's "
            "law, stiffer)"},
    {.name = "contact.self",
     .kind = K::table,
     .shown = "off",
     .doc = "contact between parts of the body: every surface node against the deformed surface away from its own "
            "neighbourhood, with the ground's law on its distance d to those triangles, k/3 (δ − d)³, d their smoothed "
            "minimum −τ log Σ exp(−dᵢ/τ) (C¹ where the nearest triangle changes in a fold). The force moves the node "
            "and the triangle's corners; the Jacobian keeps the scene's pattern with only each node's own 3×3 block "
            "(Gauss–Newton for the corners), so Newton converges more slowly while parts touch (docs/decisions.md). "
            "Unsigned: keep k high enough that no node passes through (`tools/penetration.py` measures it). IDA, "
            "backward Euler and statics; not XPBD nor the mass-spring model"},
    {.name = "contact.self.enabled",
     .kind = K::boolean,
     .fallback = "true",
     .doc = "false: the table is kept but contact between parts is off"},
    {.name = "contact.self.stiffness",
     .kind = K::number,
     .unit = "N/m³ or N/m⁴",
     .shown = "`contact.stiffness`",
     .range = Range::positive(),
     .doc = "k"},
    {.name = "contact.self.thickness",
     .kind = K::number,
     .unit = "m",
     .shown = "`contact.thickness`",
     .range = Range::positive(),
     .doc = "δ"},
    {.name = "contact.self.law",
     .kind = K::string,
     .shown = "`contact.law`",
     .choices = "node area",
     .doc = "`\"node\"` or `\"area\"`"},
    {.name = "contact.self.exclude",
     .kind = K::number,
     .unit = "m",
     .shown = "three mean surface edges",
     .range = Range::positive(),
     .doc =
         "a node's neighbourhood: triangles with a corner this close to the node at rest are not its contact partners"},
    {.name = "contact.self.smoothing",
     .kind = K::number,
     .unit = "m",
     .shown = "δ/10",
     .range = Range::positive(),
     .doc = "τ of the smoothed minimum distance (smaller: closer to the nearest triangle's distance, stiffer where it "
            "changes)"},
    {.name = "contact.self.damping",
     .kind = K::number,
     .unit = "s/m",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "α: normal damping between the parts, Hunt & Crossley's form as `contact.damping`, on the approach rate "
            "n·(v_node − Σ wᵢ v_cornerᵢ); its Jacobian keeps the own blocks only (k α p² n nᵀ, times wᵢ² on the "
            "corners). Not inherited from `contact.damping`"},
    {.name = "contact.self.friction",
     .kind = K::number,
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "only 0"},
    {.name = "contact.self.slip_speed",
     .kind = K::number,
     .unit = "m/s",
     .shown = "`contact.slip_speed`",
     .range = Range::positive(),
     .doc = "unused (no friction)"},
    {.name = "contact.plane",
     .kind = K::tables,
     .doc = "`[[contact.plane]]`: another contact plane (same law as the ground), possibly moving"},
    {.name = "contact.plane.point",
     .kind = K::vec3,
     .unit = "m",
     .range = Range::coordinate(),
     .doc = "a point on the plane at t0"},
    {.name = "contact.plane.normal", .kind = K::vec3, .doc = "normal pointing to the free side"},
    {.name = "contact.plane.stiffness",
     .kind = K::number,
     .unit = "N/m³",
     .shown = "`contact.stiffness`",
     .range = Range::positive(),
     .doc = "k"},
    {.name = "contact.plane.law",
     .kind = K::string,
     .shown = "`contact.law`",
     .choices = "node area",
     .doc = "`\"node\"` or `\"area\"`, as `contact.law`"},
    {.name = "contact.plane.damping",
     .kind = K::number,
     .unit = "s/m",
     .shown = "`contact.damping`",
     .range = Range::non_negative(),
     .doc = "α, as `contact.damping`"},
    {.name = "contact.plane.thickness",
     .kind = K::number,
     .unit = "m",
     .shown = "`contact.thickness`",
     .range = Range::positive(),
     .doc = "δ"},
    {.name = "contact.plane.friction",
     .kind = K::number,
     .shown = "`contact.friction`",
     .range = Range::non_negative(),
     .doc = "μ_c, as `contact.friction`"},
    {.name = "contact.plane.slip_speed",
     .kind = K::number,
     .unit = "m/s",
     .shown = "`contact.slip_speed`",
     .range = Range::positive(),
     .doc = "ε, as `contact.slip_speed`"},
    {.name = "contact.plane.displacement",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .doc = "the plane moves by this between t0 and t1, linearly"},
    {.name = "contact.plane.t0",
     .kind = K::number,
     .unit = "s",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "start of the motion"},
    {.name = "contact.plane.t1",
     .kind = K::number,
     .unit = "s",
     .fallback = "1",
     .range = Range::positive(),
     .doc = "end of the motion"},
    {.name = "damping", .kind = K::table, .doc = "Rayleigh damping"},
    {.name = "damping.alpha",
     .kind = K::number,
     .unit = "1/s",
     .fallback = "0",
     .range = {0.0, 1000000.0, false, false},
     .doc = "Rayleigh mass-proportional damping: f = −(α M + β K) v"},
    {.name = "damping.beta",
     .kind = K::number,
     .unit = "s",
     .fallback = "0",
     .range = {0.0, 1000.0, false, false},
     .doc = "Rayleigh stiffness-proportional damping"},
    {.name = "initial", .kind = K::table, .doc = "the initial state"},
    {.name = "initial.velocity",
     .kind = K::vec3,
     .unit = "m/s",
     .fallback = "[0, 0, 0]",
     .range = Range::speed(),
     .doc = "initial velocity of every free node (each component within ±10⁵)"},
    {.name = "initial.flatten",
     .kind = K::string,
     .fallback = "\"none\"",
     .choices = "none x y z",
     .doc = "`\"x\"`, `\"y\"` or `\"z\"`: the XPBD paper's scrambled start. Every node starts in the plane through the "
            "mesh's bounding-box centre normal to that axis, at a uniformly random point of the box in the other two "
            "axes (every tet flat: J = 0). With zones, set `zones.restore_time` (their volume is 0 at the start)"},
    {.name = "initial.seed",
     .kind = K::integer,
     .fallback = "1",
     .min = 0,
     .max = 2147483647,
     .doc = "seed of `initial.flatten`'s random points (std::mt19937_64): the same start on every run"},
    {.name = "initial.spread",
     .kind = K::number,
     .fallback = "1",
     .range = {0.0, 1.0, false, false},
     .doc = "how random `initial.flatten`'s start is: each node goes to (1 − spread) of the way from its random point "
            "to its rest position projected into the plane (0: the body squashed flat; 1: the paper's start, every "
            "node anywhere in the plane). The random points are the same for every spread. On the dragon "
            "(`demos/dragon_unfold.toml`) 0.1 unfolds to within 1% and 1 ends tangled with every method"},
    {.name = "initial.from",
     .kind = K::string,
     .doc = "a run file of the same mesh (its node count and rest positions; resolved against the scene's directory): "
            "every node starts at that run's positions and velocities at `initial.frame`. A dynamic run from a static "
            "equilibrium is `isochor run SCENE --set integrator.kind=static -o eq.h5`, then `isochor run SCENE --set "
            "initial.from=eq.h5`; an equilibrium stays put (`Statics.ADynamicRunFromAStaticEquilibriumStaysThere`). "
            "Driven nodes follow their drivers from t = 0 as always. Not with `initial.flatten` or `initial.velocity`. "
            "On IDA, zones kept must start at their rest volumes to 1e-8 (a compressible model's state does not), else "
            "`zones.restore_time` is needed"},
    {.name = "initial.frame",
     .kind = K::integer,
     .fallback = "-1",
     .min = -1000000000,
     .max = 1000000000,
     .doc = "the frame of `initial.from`: 0 the first, negative counted from the end (−1 the last)"},
    {.name = "initial.displacement",
     .kind = K::string,
     .doc = "a CSV file (columns `node,ux,uy,uz`, m; resolved against the scene's directory): each listed node starts "
            "displaced from its rest position by its row, the others at rest; velocities from `initial.velocity`. A "
            "node listed twice, a node the mesh lacks or a non-finite displacement is refused with the file and row. "
            "Not with `initial.flatten` or `initial.from`. On IDA, kept zones must start at their rest volumes to "
            "1e-8, else `zones.restore_time` is needed"},
    {.name = "collider", .kind = K::tables, .doc = "`[[collider]]`: one rigid body"},
    {.name = "collider.shape",
     .kind = K::string,
     .choices = "plane sphere capsule box cylinder mesh",
     .doc = "`\"plane\"` (the side along `axis` is free), `\"sphere\"`, `\"capsule\"` (a segment of `length` along "
            "`axis`, thickened by `radius`), `\"box\"`, `\"cylinder\"` (along `axis`: solid, or hollow with `wall` > "
            "0, so that tissue stays in its hole: a band, a sleeve), `\"mesh\"` (a closed triangle surface from "
            "`file`; tissue stays outside it)"},
    {.name = "collider.center",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .range = Range::coordinate(),
     .doc = "the shape's centre (a plane: a point on it) at rest; a mesh: where its file's origin goes"},
    {.name = "collider.axis",
     .kind = K::vec3,
     .fallback = "[0, 0, 1]",
     .doc = "the shape's axis: a plane's normal, a capsule's or cylinder's axis, a box's local z; a mesh: the axis it "
            "is turned about by `angle` (the file's own axes are kept otherwise)"},
    {.name = "collider.angle",
     .kind = K::number,
     .unit = "degrees",
     .fallback = "0",
     .doc = "the shape turned about its axis (a box's yaw)"},
    {.name = "collider.file",
     .kind = K::string,
     .doc = "mesh: a closed triangle surface, `.stl` (ASCII or binary) or `.obj`, relative to the scene file; its "
            "triangles need not be consistently oriented (inside is found by casting rays), but the surface must be "
            "closed"},
    {.name = "collider.scale",
     .kind = K::number,
     .fallback = "1",
     .range = Range::positive(),
     .doc = "mesh: the file's coordinates are multiplied by this (0.001 for a file in millimetres)"},
    {.name = "collider.cell",
     .kind = K::number,
     .unit = "m",
     .shown = "the surface's longest side / 64",
     .range = Range::positive(),
     .doc =
         "mesh: the sampling cell of its signed distance. The exact distance (CGAL's AABB tree) is sampled on a grid "
         "of this cell over the surface's bounding box grown by `thickness` + 4 cells, and the collider's distance is "
         "the cubic B-spline through those samples: C², so the force is C¹ and its Jacobian exact. Flat faces more "
         "than two cells from an edge are exact; edges, corners and details smaller than about two cells are rounded; "
         "near a surface of curvature radius r the distance is h²/(3r) larger than the exact one. Setup costs one tree "
         "query per sample: about 0.6M samples and 4 s for `demos/ball_on_torso.toml`'s 5 mm cells"},
    {.name = "collider.radius",
     .kind = K::number,
     .unit = "m",
     .range = Range::length(),
     .doc = "sphere, capsule; cylinder: its radius (hollow: the hole's)"},
    {.name = "collider.length",
     .kind = K::number,
     .unit = "m",
     .range = Range::length(),
     .doc = "capsule: its axis segment; cylinder: its height"},
    {.name = "collider.size", .kind = K::vec3, .unit = "m", .doc = "box: edge lengths along its local x, y, z"},
    {.name = "collider.wall",
     .kind = K::number,
     .unit = "m",
     .fallback = "0",
     .range = {0.0, 1000000.0, false, false},
     .doc = "cylinder: the wall thickness of a hollow one (0: solid)"},
    {.name = "collider.rounding",
     .kind = K::number,
     .unit = "m",
     .shown = "a tenth of the smallest half dimension",
     .range = Range::non_negative(),
     .doc = "box, cylinder: radius of the rounded edges, at most the smallest half dimension"},
    {.name = "collider.stiffness",
     .kind = K::number,
     .unit = "N/m³ or N/m⁴",
     .shown = "`contact.stiffness`",
     .range = Range::positive(),
     .doc = "k, as `contact.stiffness`"},
    {.name = "collider.thickness",
     .kind = K::number,
     .unit = "m",
     .shown = "`contact.thickness`",
     .range = Range::positive(),
     .doc = "δ"},
    {.name = "collider.law",
     .kind = K::string,
     .shown = "`contact.law`",
     .choices = "node area",
     .doc = "`\"node\"` or `\"area\"`, as `contact.law`"},
    {.name = "collider.damping",
     .kind = K::number,
     .unit = "s/m",
     .shown = "`contact.damping`",
     .range = Range::non_negative(),
     .doc = "α, as `contact.damping` (relative to the collider's moving surface)"},
    {.name = "collider.friction",
     .kind = K::number,
     .shown = "`contact.friction`",
     .range = Range::non_negative(),
     .doc = "μ_c, as `contact.friction`"},
    {.name = "collider.slip_speed",
     .kind = K::number,
     .unit = "m/s",
     .shown = "`contact.slip_speed`",
     .range = Range::positive(),
     .doc = "ε, as `contact.slip_speed`"},
    {.name = "collider.motion",
     .kind = K::table,
     .like = "boundary",
     .shown = "static",
     .doc = "how it moves, with the keys of a `[[boundary]]` driver: `{ kind = \"ramp\", displacement = [..], t0, t1 "
            "}`, `{ kind = \"keyframes\", times, values, interpolation }`, `{ kind = \"sinusoid\", amplitude, "
            "frequency, phase }`, or `{ kind = \"rotation\", times, angles, center, axis, interpolation }` (turning "
            "about `motion.axis` through `motion.center`)"},
    {.name = "collider.resize",
     .kind = K::table,
     .doc = "the radius changes in time (a band that tightens): `{ times = [..], factors = [..], interpolation = "
            "\"linear\" or \"cubic\" }`, the radius (a hollow cylinder's hole; its wall and rounding stay) times the "
            "factor at each time, held outside them. Sphere, capsule and cylinder; not with `damping` or `friction`"},
    {.name = "collider.resize.times", .kind = K::numbers, .unit = "s", .doc = "keyframe times (increasing)"},
    {.name = "collider.resize.factors",
     .kind = K::numbers,
     .range = Range::positive(),
     .doc = "the factor on the radius at each time"},
    {.name = "collider.resize.interpolation",
     .kind = K::string,
     .fallback = "\"linear\"",
     .choices = "linear cubic",
     .doc = "`\"cubic\"`: C¹ (Catmull–Rom, zero rate at the first and last keys)"},
    {.name = "collider.bone",
     .kind = K::string,
     .doc = "carried rigidly by this bone of `[skeleton]` (the pose above is its rest pose); excludes `motion`"},
    {.name = "integrator", .kind = K::table, .doc = "the method and its settings"},
    {.name = "integrator.kind",
     .kind = K::string,
     .fallback = "\"ida\"",
     .choices = "ida static backward_euler semi_implicit xpbd mass_spring",
     .doc =
         "`\"ida\"` (adaptive BDF on the GGL DAE), `\"backward_euler\"` (fixed step `dt`, Newton to convergence on the "
         "KKT system per step), `\"semi_implicit\"` (one Newton step per step), `\"static\"` (KINSOL: equilibrium at "
         "every frame, drivers at pseudo-time 0..1 over `frames.count`), `\"xpbd\"` (Macklin & Müller's deviatoric and "
         "hydrostatic constraints per tet, energy of `snh_simple` with the material's μ and λ; zones as hard "
         "constraints; the ground as a collision plane; no Rayleigh damping); `\"mass_spring\"` (Hong et al.'s step "
         "for `material.model = \"mass_spring\"`: symplectic Euler with the enclosed-volume constraint enforced "
         "implicitly, one scalar per step). An option that the kind does not take (e.g. `hessian` with `\"ida\"`) is "
         "refused, unless `kind` itself comes from `--set` (or a study's `set`) and the option from the file: a scene "
         "written for one method then runs as a variant of another, its own method's options unused "
         "(`demos/dragon_unfold.toml`: backward Euler in the file, IDA and XPBD by `--set integrator.kind=…`)"},
    {.name = "integrator.rtol",
     .kind = K::number,
     .fallback = "1e-6",
     .range = {0.0, 1.0, true, false},
     .doc = "relative tolerance (IDA)"},
    {.name = "integrator.atol",
     .kind = K::number,
     .unit = "m",
     .fallback = "1e-8",
     .range = Range::length(),
     .doc = "absolute tolerance on positions (IDA)"},
    {.name = "integrator.dt",
     .kind = K::number,
     .unit = "s",
     .fallback = "1e-3",
     .range = Range::positive(),
     .doc =
         "fixed step (backward Euler, semi-implicit, XPBD); frames between steps are interpolated linearly (backward "
         "Euler and semi-implicit with constraints: then projected onto them, positions onto g = 0 and velocities onto "
         "G v + ∂g/∂t = 0 in the mass norm, as IDA's frames, so that every frame keeps every zone's volume)"},
    {.name = "integrator.newton_tol",
     .kind = K::number,
     .fallback = "1e-6",
     .range = Range::positive(),
     .doc =
         "backward Euler: Newton stops when its estimated error in the positions, r/(1 − r)·|Δq|with r the contraction "
         "rate of the iterations since the last factorisation (IDA's test), is at most this times the step's "
         "displacement max|q − qₙ|plus `newton_atol`: a relative accuracy of the step's velocity, the same at every "
         "`dt`. A first iteration (no rate measured in this step) stops at once only if its update is below 1e-4 of "
         "that tolerance; it stops after the step's residual at the new q confirms it (h²|r|/M and|g|/|∇g|within the "
         "tolerance, one force evaluation and no solve) if the update is within the tolerance, or within it once "
         "multiplied by r/(1 − r) of the rate the current matrix showed on earlier steps (not with KLU's KKT matrix, "
         "which keeps the constraint rows of its factorisation while the body turns), and in both cases only if the "
         "multipliers moved by at most `newton_tol` of their size. On the MEBDFDAE pendulum and the car axis the "
         "`reduced` solver so takes one iteration per step with exact Newton's answer (`docs/results/tolerance.md`). "
         "The step matrix is factored afresh when an iteration contracts by less than 4×, or when the iterations a "
         "kept matrix has cost beyond those of the step that factored it outweigh a fresh matrix (both estimated from "
         "counts: the forces and solves per iteration against the Hessian's assembly and the factorisation; "
         "`docs/decisions.md`), and a step whose reused matrix stalls (r > 0.9) is redone with fresh ones"},
    {.name = "integrator.newton_atol",
     .kind = K::number,
     .unit = "m",
     .fallback = "1e-12",
     .range = Range::positive(),
     .doc = "backward Euler: the floor of Newton's tolerance, for steps that barely move (a body at rest)"},
    {.name = "integrator.max_newton",
     .kind = K::integer,
     .shown = "30 (backward Euler), 4 (IDA)",
     .min = 1,
     .max = 100000,
     .doc = "backward Euler: Newton iterations allowed per step before the step fails (or is halved, "
            "`substeps_on_failure`); IDA (1..100): iterations per step attempt before IDA counts a convergence failure "
            "and retries with a fresh Jacobian or a quarter of the step (IDASetMaxNonlinIters)"},
    {.name = "integrator.dense_border_rows",
     .kind = K::integer,
     .fallback = "8",
     .min = 0,
     .max = 100000,
     .doc =
         "backward Euler and semi-implicit: constraint rows (zones and support rows) up to which each Newton "
         "iteration solves the step matrix alone and the rows' border by a dense Schur complement (m + 1 solves with "
         "the step matrix's solver); above, the whole KKT matrix is factored (KLU up to 32 rows, UMFPACK above; "
         "always with `linear_solver = \"klu\"`). Measured on the clamped beam with 1 to 32 zones, 50 steps "
         "(`bench/dense_border.sh`): the dense border costs 0.087 s per row at 6,480 tets and 0.40 s at 21,870, the "
         "KKT path a fixed 0.67 and 4.1 s and 0.012 and 0.098 per row; they cross near 4 rows on the first mesh "
         "and near 9 on the second, and at 32 rows the dense border took 3.0 and 1.9 times as long "
         "(`docs/results/zones_cost.md`). On MPI "
         "ranks the dense border is kept up to 32 rows (the KKT matrix is factored on one process)"},
    {.name = "integrator.line_search",
     .kind = K::boolean,
     .fallback = "true",
     .doc =
         "backward Euler: solve each step as a minimisation. Without damping, the step minimises the incremental "
         "potential Φ(q) = ½‖q − qₙ − h vₙ‖²_M / h² + V(q) subject to the zone constraints: each Newton direction is "
         "cut back by halving until the exact ℓ1 merit Φ + Σ νⱼ|gⱼ|(νⱼ = 2|λⱼ|, growing within a step) decreases by "
         "Armijo's rule; a matrix that cannot be factored, or a direction that does not descend, is retried with its "
         "inertia term M/h² scaled by 2, 11, 101, … up to 10⁶ (Levenberg–Marquardt in the mass metric); the start of "
         "each step is the velocity extrapolation or qₙ + h vₙ, whichever has the lower merit. Where the scene damps "
         "(Rayleigh, the planes' `damping`), the damping is made variational: its matrix −∂f/∂v is frozen per step at "
         "qₙ (elements projected only with `hessian = \"projected\"`), and the step's damping force is −D (q − qₙ)/h "
         "(plus that of the driven nodes' motion at qₙ), so Φ gains ½ (q − qₙ)ᵀ D (q − qₙ)/h and the Jacobian is exact "
         "(with `false`, β K(q) v is evaluated at every iterate, as before: the same order of accuracy, a different "
         "first-order error). A search that fails with a reused matrix is redone with a fresh one. Updates within 100× "
         "Newton's tolerance are taken whole; where every update is taken whole the run is the same as `false` (plain "
         "Newton). Off where the scene has no potential (a `kind = \"pressure\"` load). `ISOCHOR_TRACE_NEWTON=T` in "
         "the environment prints every Newton iteration of the steps after time T (step length, update, residual)"},
    {.name = "integrator.hessian",
     .kind = K::string,
     .fallback = "\"exact\"",
     .choices = "exact projected hybrid",
     .doc = "backward Euler and semi-implicit: `\"projected\"` fills the step matrix with every element's Hessian "
            "projected onto the positive semi-definite matrices (negative eigenvalues set to 0, as Teran et al. and "
            "HOBAK do); the forces stay exact, so a converged step is the same, but Newton converges only linearly "
            "where elements are inverted or strongly compressed. `\"hybrid\"` (backward Euler with the line search): "
            "projected until two Newton updates in a row are taken whole, then exact for the rest of the step "
            "(quadratic convergence near the solution; on the scrambled SNH cube of `demos/scramble.toml` at 6³ cells "
            "the projected iteration contracted at 0.93 per iteration and failed after 100, the hybrid ran the 1 s)"},
    {.name = "integrator.substeps_on_failure",
     .kind = K::integer,
     .shown = "0 (backward Euler), 5 (static)",
     .min = 0,
     .max = 30,
     .doc = "backward Euler: a step that fails is retried as two half steps, each of which may be halved again, up to "
            "this many levels; counted in `/stats step_halvings`. Off by default so that a stability map says where "
            "the step itself fails. Static: a load increment (frame to frame) that KINSOL cannot solve is solved as "
            "two half increments from the last equilibrium, halved again on failure; on by default (pseudo-time has no "
            "accuracy to lose); a failure then names the pseudo-time it started from and the halvings"},
    {.name = "integrator.atol_v",
     .kind = K::number,
     .unit = "m/s",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "IDA: absolute tolerance on velocities; 0 stands for 100·`atol` per second, which caps the accuracy of the "
            "velocities at tight `rtol` (set it to go below)"},
    {.name = "integrator.atol_lambda",
     .kind = K::number,
     .unit = "Pa (volume constraints)",
     .fallback = "0",
     .range = Range::non_negative(),
     .doc = "IDA: absolute tolerance on the multipliers in Newton's convergence test (they are algebraic and out of "
            "the error test); 0 stands for 1e-6 of the force scale (the body's weight or μ·V^(2/3)); divided "
            "by|G_j|per constraint"},
    {.name = "integrator.substeps",
     .kind = K::integer,
     .fallback = "10",
     .min = 1,
     .max = 100000,
     .doc = "XPBD: substeps per step `dt`"},
    {.name = "integrator.iterations",
     .kind = K::integer,
     .fallback = "1",
     .min = 1,
     .max = 100000,
     .doc = "XPBD: Gauss–Seidel sweeps over all constraints per substep (tets in mesh order, deviatoric before "
            "hydrostatic, then zones)"},
    {.name = "integrator.rescale_volume",
     .kind = K::boolean,
     .fallback = "false",
     .doc = "backward Euler and semi-implicit: after each step, scale the free nodes about the centre of mass so that "
            "the total volume is the rest volume again (the CNH paper's naive rescaling baseline; velocities are left "
            "as they are)"},
    {.name = "integrator.weights_center",
     .kind = K::vec3,
     .unit = "m",
     .fallback = "[0, 0, 0]",
     .doc = "mass_spring step: centre of Hong's deformation zone"},
    {.name = "integrator.weights_radius",
     .kind = K::number,
     .unit = "m",
     .fallback = "0",
     .shown = "0 (uniform)",
     .range = Range::non_negative(),
     .doc = "mass_spring step: the constraint force on surface node i is scaled by W_i = (cos(π d_i / r) + 1)/2 for "
            "d_i < r, 0 beyond, normalised to sum to the number of nodes (Hong et al.'s eq. 15, whose π the converted "
            "text lost). Zones that leave much of the surface at zero weight pump energy into the model and blow up "
            "(measured on demos/probe_ball.toml with r = 0.12 m); r = 0.3 m is stable there"},
    {.name = "integrator.max_order",
     .kind = K::integer,
     .fallback = "5",
     .min = 1,
     .max = 5,
     .doc = "largest BDF order (IDA), 1..5"},
    {.name = "integrator.max_step",
     .kind = K::number,
     .unit = "s",
     .fallback = "0",
     .shown = "0 (none)",
     .range = Range::non_negative(),
     .doc = "largest step (IDA)"},
    {.name = "integrator.newton_coef",
     .kind = K::number,
     .fallback = "0.05",
     .range = {0.0, 1.0, true, true},
     .doc = "IDA: Newton stops when its error estimate is below this fraction of the tolerance (IDASetNonlinConvCoef), "
            "the same for every linear solver. At IDA's own 0.33 the Newton error moves the error estimates and so the "
            "steps differently on each solver (the test DAEs' fitted accuracies 0.1–0.13 digit apart); at 0.05 they "
            "agree within 0.08 with fewer steps in total (docs/results/tolerance.md)"},
    {.name = "integrator.jacobian_age",
     .kind = K::integer,
     .unit = "steps",
     .fallback = "0",
     .min = 0,
     .max = 1000000000,
     .doc = "IDA: when IDA asks for a new matrix only because its step (c_j) changed, reuse the last assembled "
            "Jacobian with the new c_j (it enters only the diagonals c_j I and c_j M) if it is at most this many steps "
            "old and Newton has not failed since; 0 assembles at every setup. With `krylov` such a setup moves the "
            "solver's last setup to the new c_j in place (no copy of the matrix, no new factor; counted in `/stats "
            "retargets`) and keeps Newton's rate estimate. 20 saves 11% of the coarse ball's run (60 ms: 139 instead "
            "of 398 assemblies for as many steps)|`ISOCHOR_TRACE_IDA=T` in the environment prints one line per IDA "
            "step after time T (step, order, failures so far, the shares of the weighted local error held by positions "
            "and velocities, and the three free dofs that weigh most, as `free node.axis`), each Newton residual's "
            "largest entry per block, and why a linear setup or solve failed: where IDA's time goes. "
            "`ISOCHOR_CAPTURE_S=T:PATH` writes the effective stiffness S of the first setup at or after time T (linear "
            "solvers `reduced`, `krylov`, `amg`) with the right-hand side of its first solve, once, to PATH "
            "(`bench/amg_s.sh` reads it; layout in `sparse_factor.hpp`)"},
    {.name = "integrator.linear_tol",
     .kind = K::number,
     .fallback = "0",
     .range = {0.0, 0.01, false, true},
     .doc = "With `linear_solver` `krylov` or `amg` (chosen or automatic): the relative residual at which CG stops. "
            "Backward Euler: 0 takes 1e-4. Its Newton test measures its own contraction and stops on its estimated "
            "error, so a CG stopped early (an inexact Newton direction, still one of descent) moves work from CG to "
            "Newton, not the accuracy of a step: on the 105K-tet pinned cube (26³ cells, 2 s) 1e-4 took 51 CG "
            "iterations per solve against 158 at 1e-12, 570 Newton iterations against 571, and 53 s against 115 s, "
            "with frames within 9e-8 m of CHOLMOD's (Newton's own tolerance there is ~6e-6 m); 1e-3 took 49 s, 4e-7 m. "
            "IDA: 0 takes min(1e-12, 1e-6 · rtol), tight enough for every scene tried (the undamped 600-tet ball at "
            "rtol 1e-8 needed 1e-14). A looser stop makes Newton inexact: where S ≈ c_j² M (steps of microseconds) it "
            "costs few Newton iterations and saves CG iterations. On the 16³ collapse to 0.2 s at rtol 1e-4, 1e-6 took "
            "2.4 CG iterations per solve against 4.5 and halved the solve time (8.0 → 4.4 s of 37 s), with positions "
            "1e-8 (relative) from the default's at 80 ms. On the 1,000-tet ball at rtol 1e-6, 1e-8 keeps the frames to "
            "the integration tolerance (`IdaRun.BallDropFramesAgreeAcrossLinearSolvers`)"},
    {.name = "integrator.max_steps",
     .kind = K::integer,
     .fallback = "10000000",
     .shown = "10⁷",
     .min = 1,
     .max = 1000000000000,
     .doc = "steps allowed over the whole run; more is a failure"},
    {.name = "integrator.stop_at_frames",
     .kind = K::boolean,
     .fallback = "false",
     .doc = "IDA: end a step on every frame time as well. By default IDA steps freely, ending steps only at the "
            "scene's breakpoints (below) and the last frame; each frame is IDA's interpolated state (IDAGetDky) "
            "projected onto the constraints (positions onto g = 0, velocities onto G v + ∂g/∂t = 0, each the nearest "
            "point in the mass norm), so every frame keeps every zone's volume to rounding either way. `true` costs "
            "steps where frames are dense (IDA held at low order) and is there for comparisons"},
    {.name = "integrator.linear_solver",
     .kind = K::string,
     .fallback = "\"auto\"",
     .choices = "auto klu reduced krylov amg",
     .doc =
         "`\"auto\"`, `\"klu\"`, `\"reduced\"`, `\"krylov\"` or `\"amg\"`. `\"auto\"`: IDA `krylov` for a mesh with at "
         "most 256 constraint rows (zones and support rows), else `klu` (measured on the ball through its impact: "
         "`krylov` 2.5 times faster than `klu` at 320 tets, 48 times at 4.5K, and faster than `reduced` from 966 tets "
         "up; its cost grows with the rows, ~0.05 s per zone on a 6K-tet box, where 125 zones ran 4.7 times faster "
         "than KLU on the GGL matrix; against `klu` through the KKT matrix, below, it depends on the rows' width and "
         "the setups per step: on that box in its first 20 ms, 9 setups in 11 steps, 125 1-ring-sized patches took "
         "8.9 s on `krylov` and 1.0 s on `klu`, while the 21,870-tet beam over 50 ms, 5 setups in 261 steps, with "
         "108 2-ring patches took 12.2 s on `krylov` and 28.7 s on `klu`, single runs: the threshold stays); backward "
         "Euler `krylov` where its step has the line search (the default where the scene "
         "has a potential) and at least 1,300 free dofs, else `reduced` (measured on the pinned cube, one thread, 120 "
         "frames, side by side: the two tie at 1,344 dofs, 7³ cells, 3.4 ms per frame; `krylov` is 1.4 times faster at "
         "7,644 dofs, 13³; at 57K, 26³, 0.63 s per frame against CHOLMOD's 2.66 s (4.2 times; one after the other on "
         "one core, another run on the other), CHOLMOD's factorisations growing faster than the matrix: "
         "`docs/results/pinned_cube.md`; without the line search a matrix PCG finds indefinite would stop the step, "
         "with it the matrix is shifted); then, with the line search, after every step once the solver in use has "
         "taken 4 steps, the cost per Newton iteration of each is estimated from what those steps counted (no clock: a "
         "run repeats): PCG's from its CG iterations, CHOLMOD's from the fresh matrices per Newton iteration and its "
         "factor's flops and entries (CHOLMOD's symbolic analysis; above 20,000 dofs made only once CG takes 100 "
         "iterations per Newton iteration), and the step switches to the other when it is estimated 1.5 times cheaper "
         "(counted in `/stats solver_switches`; `bench/auto_solver.sh`, medians of 4 side-by-side rounds on one "
         "thread: on the Figure 8 cube in UNH, SNH and CNH at 8 and 33 ms, where CG takes 140–580 iterations per "
         "Newton iteration, auto took 0.8–1.37 times the faster solver's time where PCG alone took up to 4.4 times and "
         "CHOLMOD alone up to 1.25; the pinned cube at 13³ stays on PCG, at 7³ and on the twist it moves to CHOLMOD, "
         "within 4% of the faster); semi-implicit `reduced`; statics `klu`, or `reduced` above 64 constraint rows "
         "(1-ring zones, fine patches, rollers as rows: its sparse border, below; Cook's membrane at N = 32 with a "
         "roller row per node took 17.3 s on `klu` and 3.2 s on `reduced`, with 1-ring zones as well 99.3 s and 12.7 "
         "s: `docs/results/zones_cost.md`). `\"klu\"`: KLU on the whole matrix (IDA: the (6n+2m) GGL matrix, up to 32 "
         "constraint rows; above, the GGL system through its (3n+m) KKT matrix [S Gᵀ; B + c G 0] by UMFPACK and the "
         "sparse G Gᵀ, refined against the GGL matrix until the estimated error is 1e-4 in IDA's weighted norm (the "
         "refinement steps counted in `/stats linear_iterations`; where they do not converge, at large steps on stiff "
         "contact, the GGL matrix's own UMFPACK factor for that setup, counted in `linear_fallbacks`): the same steps "
         "and frames to 1e-12 m, the 6,480-tet beam with 1,516 1-ring zones 5.9 s against KLU's 53 s (bench medians); "
         "backward "
         "Euler and statics: the KKT matrix, by UMFPACK instead above 32 constraint rows, 9 times faster to factor "
         "with the beam's 4,600 1-ring rows: `docs/decisions.md`). `\"reduced\"`: eliminate the velocity update and "
         "factor only the n×n "
         "effective stiffness S = c²M − c ∂f/∂v − ∂f/∂q + Σλ H with CHOLMOD (METIS, supernodal LLᵀ; a simplicial LDLᵀ "
         "while S is indefinite, LLᵀ tried again every 8 factorisations; not in backward Euler with the line search, "
         "which shifts an indefinite S by more inertia as it does with PCG: LDLᵀ's directions there descended poorly, "
         "and the 4.7K-tet ball at 1 ms failed at 36 ms where it now runs), the 2m constraint borders by a Schur "
         "complement (backward Euler: the KKT matrix above `dense_border_rows` constraints, as `klu`). `\"krylov\"`: "
         "as `reduced`, but "
         "S "
         "solved by conjugate gradients with the inverses of its 3×3 nodal blocks as preconditioner (relative residual "
         "1e-12, tighter for IDA below rtol 1e-6): no factor, memory proportional to the matrix; in IDA, where CG "
         "fails (S indefinite where elements invert, or no convergence) that setup's solves fall back to a CHOLMOD "
         "factor of S (counted in `/stats linear_fallbacks`), and the next setup tries CG again; IDA retries a smaller "
         "step only if that fails too. In IDA every solver keeps its matrix at the setup's c_j between setups and "
         "scales the correction by 2/(1 + c_j/c_j,setup), as IDA does, so that all take the same steps and give the "
         "same error at one tolerance (`docs/results/tolerance.md`; moving `krylov`'s S to each new c_j took 8% fewer "
         "Newton iterations on the 16³ collapse but other steps, and the pendulum's error at one tolerance moved by up "
         "to 0.8 digit). `\"amg\"`: as `krylov`, but CG preconditioned by one V-cycle of hypre's BoomerAMG (nodal HMIS "
         "coarsening, extended+i interpolation, symmetric Gauss–Seidel; a new hierarchy at every setup), with the same "
         "tolerance and fallback; only in builds with hypre and MPI (Debian's `libhypre-dev`, `libopenmpi-dev`: the "
         "README's commands install them), else the key is refused; on MPI ranks each rank hands hypre its own rows of "
         "S and CG runs across them (`docs/scale.md`); measured against `krylov` in `docs/results/linear_solvers.md`. "
         "In IDA, CG's relative residual is min(1e-12, 1e-6 · rtol): with 1e-12 at rtol 1e-8, atol 1e-11, the 600-tet "
         "undamped ball failed at 92 ms (IDA_CONV_FAIL; `reduced` ran), with 1e-14 it runs. Statics: "
         "`reduced`/`krylov` solve the KKT system through its n×n block A = K + Σλ H (CHOLMOD or PCG; PCG needs A "
         "positive definite, e.g. every node's motion resisted) and the m borders by a Schur complement: dense (m + 1 "
         "solves per Newton iteration) up to 64 rows or with PCG; above 64 rows with `reduced` the sparse border: each "
         "row on at most 384 dofs enters A as a penalty ρⱼ gⱼgⱼᵀ (which leaves the solution unchanged), A + Gᵀ D G is "
         "factored once by CHOLMOD, and the Schur complement is solved by conjugate gradients preconditioned by D to "
         "1e-10, with one pass of refinement against the KKT system itself (the augmented-Lagrangian preconditioner; "
         "ρⱼ = 100 × A's mean diagonal over the row's dofs / ‖gⱼ‖², raised tenfold up to 10⁴ while CHOLMOD finds A + "
         "GᵀDG indefinite; CG iterations counted in `/stats linear_iterations`; `integrators/src/bordered.hpp`). "
         "Before that, support rows on one dof (a roller, a held component along an axis) take their dof out of A: it "
         "is fixed by its row alone, and the row's multiplier follows from its dof's equation (exact; Cook's membrane "
         "in plane strain at N = 64 with 1-ring zones, one thread: 20 s instead of 52 s, the same displacement: "
         "`docs/results/zones_cost.md`). Where it cannot solve a setup (A + GᵀDG still indefinite, CG failing, or its "
         "answer leaving a KKT residual above 1e-8 of the right-hand side: nearly dependent rows, as 1-ring zones make "
         "in a 3-D block), that setup and the rest of the run go to KLU on the KKT matrix (`/stats linear_fallbacks`; "
         "CG gives up after 200 iterations a pass; the pressure cube with 1-ring zones, one run each, one thread: one "
         "fallback, the same 15 Newton iterations as KLU's and 18.5 s against 31.7 s, the same equilibrium to 7e-14)"},
    {.name = "integrator.ordering",
     .kind = K::string,
     .fallback = "\"metis\"",
     .choices = "metis colamd amd",
     .doc = "fill-reducing ordering of KLU's sparse LU: `\"metis\"` (nested dissection of the node graph, each "
            "node's dofs together, multipliers last), `\"colamd\"`, `\"amd\"` (KLU's own); above 32 constraint "
            "rows UMFPACK factors in its own order (`linear_solver`)"},
    {.name = "frames", .kind = K::table, .doc = "the frames written"},
    {.name = "frames.rate",
     .kind = K::number,
     .unit = "1/s",
     .fallback = "100",
     .range = Range::positive(),
     .doc = "frames per second"},
    {.name = "frames.duration",
     .kind = K::number,
     .unit = "s",
     .fallback = "1",
     .range = Range::non_negative(),
     .doc = "simulated time"},
    {.name = "frames.count",
     .kind = K::integer,
     .min = 1,
     .max = 1000000,
     .doc = "statics: number of frames (load increments) at pseudo-times t = 0, 1/(count−1), …, 1 (drivers are "
            "evaluated at t; count = 1 solves at t = 1); excludes `rate` and `duration`"},
    {.name = "output", .kind = K::table, .doc = "the run file"},
    {.name = "output.path",
     .kind = K::string,
     .shown = "`out/<scene name>.h5`",
     .doc = "the HDF5 file; the XDMF sidecar goes beside it (`.xdmf`)"},
    {.name = "output.pressure",
     .kind = K::boolean,
     .fallback = "false",
     .doc = "write the per-tet pressure of every frame"},
};

}  // namespace

const KeyTable& scene_keys() {
  static const KeyTable table("core/src/scene_keys.cpp", {std::begin(kRows), std::end(kRows)});
  return table;
}

}  // namespace isochor
