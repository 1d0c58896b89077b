// A unit cube of tets of size h = 1 / N (Gmsh's unstructured 3-D mesher; mesh.edge_length
// overrides h), for the inf-sup test of zone choices in three dimensions (bench/infsup.sh):
// "clamp" is the face x = 0, the other faces are free.
DefineConstant[ N = 4 ];
h = 1 / N;
Point(1) = {0, 0, 0, h};
Point(2) = {0, 1, 0, h};
Point(3) = {0, 1, 1, h};
Point(4) = {0, 0, 1, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
out[] = Extrude{1, 0, 0}{ Surface{1}; };
Physical Volume("block") = {out[1]};
Physical Surface("clamp") = {1};
