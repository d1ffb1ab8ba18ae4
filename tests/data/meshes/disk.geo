// A disk of radius 60 mm in unstructured triangles, its rim a physical curve.
SetFactory("OpenCASCADE");
Disk(1) = {0, 0, 0, 60};
MeshSize{:} = 6;
Physical Surface("disk") = {1};
Physical Curve("rim") = {1};
