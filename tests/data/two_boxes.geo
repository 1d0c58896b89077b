// Two unit boxes side by side, each a physical volume; the bottom faces a physical surface.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Physical Volume("left") = {1};
Physical Volume("right") = {2};
Physical Surface("bottom") = Surface In BoundingBox{-0.1, -0.1, -0.1, 2.1, 1.1, 0.1};
Mesh.MeshSizeMax = 0.3;
