// The 160 x 160 mm blank of examples/hemisphere.toml as 8 mm quadrangles, with groups.
Point(1) = {-80, -80, 0}; Point(2) = {80, -80, 0}; Point(3) = {80, 80, 0};
Point(4) = {-80, 80, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve {1, 2, 3, 4} = 21; Transfinite Surface {1}; Recombine Surface {1};
Physical Point("corner", 5) = {4}; Physical Curve("clamped", 3) = {4};
Physical Surface("blank", 1) = {1};
