// Cook's membrane (Cook 1974; the nearly incompressible benchmark of Simo and Rifai 1990, Reese
// et al. 1999): a tapered panel clamped on its left edge (x = 0) and sheared on its right edge
// (x = 48), meshed by Gmsh into tets of size h = 48 / N, one element thick (thickness h; with
// rollers on the faces z = 0 and z = h it is a plane-strain panel). Physical groups: "clamp"
// (x = 0), "load" (x = 48), "front" (z = 0), "back" (z = h), the volume "membrane".
// isochor reads it with [mesh] file = "meshes/cook.geo"; mesh.edge_length overrides h.
DefineConstant[ N = 8 ];
h = 48 / N;
Point(1) = {0, 0, 0, h};
Point(2) = {48, 44, 0, h};
Point(3) = {48, 60, 0, h};
Point(4) = {0, 44, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
out[] = Extrude{0, 0, h}{ Surface{1}; };
// out[0]: the face at z = h, out[1]: the volume, out[2..5]: the sides swept from lines 1..4.
Physical Volume("membrane") = {out[1]};
Physical Surface("clamp") = {out[5]};
Physical Surface("load") = {out[3]};
Physical Surface("front") = {1};
Physical Surface("back") = {out[0]};
