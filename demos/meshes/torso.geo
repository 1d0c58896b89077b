// isochor's waistband torso (demos/waistband.toml): hips, two thigh stumps cut flat at z = 0, a
// waist, a belly, a chest and two breasts, as OpenCASCADE primitives fused. Metres, z up, the body
// facing -y. The surface torso.stl is made from this file by tools/make_torso.sh (Gmsh), and
// painted by tools/paint_torso.py (torso_paint.ply). OCC could not fillet the fused junctions
// (it fails at radii 0.01-0.025 m; at 0.005 m the filleted periodic surfaces do not mesh), so the
// junctions are creases: the waist, where the band acts, is one smooth ellipsoid.
SetFactory("OpenCASCADE");
Geometry.NumSubEdges = 40;
// Trunk: hips (z 0.08-0.30), waist and chest as three ellipsoids along z.
Sphere(1) = {0, 0, 0.18, 1};  Dilate {{0, 0, 0.18}, {0.17, 0.12, 0.13}} { Volume{1}; }
Sphere(2) = {0, 0, 0.40, 1};  Dilate {{0, 0, 0.40}, {0.13, 0.125, 0.22}} { Volume{2}; }
Sphere(3) = {0, 0, 0.58, 1};  Dilate {{0, 0, 0.58}, {0.16, 0.11, 0.12}} { Volume{3}; }
// Belly: a soft front bulge below the navel.
Sphere(4) = {0, -0.035, 0.30, 1};  Dilate {{0, -0.035, 0.30}, {0.11, 0.09, 0.10}} { Volume{4}; }
// Thigh stumps.
Sphere(5) = {-0.085, 0, 0.06, 1};  Dilate {{-0.085, 0, 0.06}, {0.075, 0.075, 0.16}} { Volume{5}; }
Sphere(6) = { 0.085, 0, 0.06, 1};  Dilate {{ 0.085, 0, 0.06}, {0.075, 0.075, 0.16}} { Volume{6}; }
// Breasts.
Sphere(7) = {-0.075, -0.085, 0.56, 0.06};
Sphere(8) = { 0.075, -0.085, 0.56, 0.06};
v() = BooleanUnion{ Volume{1}; Delete; }{ Volume{2:8}; Delete; };
// The thighs cut flat at z = 0.
Box(20) = {-1, -1, 0, 2, 2, 2};
BooleanIntersection{ Volume{v()}; Delete; }{ Volume{20}; Delete; }
Mesh.MeshSizeMax = 0.018;
Mesh.MeshSizeMin = 0.008;
Mesh.MeshSizeFromCurvature = 12;
Mesh.Binary = 1;
