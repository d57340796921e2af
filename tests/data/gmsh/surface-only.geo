// The same box with a Physical Surface only: gmsh saves the boundary triangles alone.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 2};
Mesh.MeshSizeMin = 0.6;
Mesh.MeshSizeMax = 0.6;
Physical Surface("skin") = {1, 2, 3, 4, 5, 6};
