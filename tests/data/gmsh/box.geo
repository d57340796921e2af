// A 1 x 1 x 2 box, meshed coarsely: the gmsh fixtures of tests/io (see README.md).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 2};
Mesh.MeshSizeMin = 0.6;
Mesh.MeshSizeMax = 0.6;
Physical Volume("body") = {1};
