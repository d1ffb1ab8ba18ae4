// A 10 x 20 x 5 mm box in tetrahedra, no physical groups: all elements are saved.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 10, 20, 5};
MeshSize{:} = 3;
