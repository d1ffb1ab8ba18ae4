// A disk of radius 60 mm with an off-centre hole of radius 15 mm, meshed unstructured and
// recombined by the simple algorithm, which leaves some triangles among the quadrangles; the
// hole's edges are on the border. `gmsh ring.geo -2 -format msh41` (Gmsh 4.15.2).
SetFactory("OpenCASCADE");
Disk(1) = {0, 0, 0, 60};
Disk(2) = {12, 7, 0, 15};
BooleanDifference(3) = { Surface{1}; Delete; }{ Surface{2}; Delete; };
MeshSize{:} = 7;
Mesh.RecombineAll = 1;
Mesh.Algorithm = 6;
Mesh.RecombinationAlgorithm = 0;
Physical Surface("ring") = {3};
