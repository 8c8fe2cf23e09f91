// Example 2 guide wire (FORMULATION.md Part III §10), built straight THROUGH the grommet centre
// (h, -e, 0): from (-0.1, -e, 0) to (2h+0.1, -e, 0) with h = 0.5 m, e = 0.02 m; L_w = 1.2 m,
// 12 segments. The scenario then moves both anchors by dy = 5 mm in +Y (prescribed coordinates,
// reached in the initial static solve) to G0 = (-0.1, -e+dy, 0), G1 = (2h+0.1, -e+dy, 0): a
// wire meshed on the anchor line would not pass through the 2 mm bore at t = 0.
// Regenerate the .msh with:  python meshes/generate.py guide_wire.geo
y = -0.02;
Point(1) = {-0.1, y, 0, 1.0};
Point(2) = {1.1, y, 0, 1.0};
Line(1) = {1, 2};
Transfinite Curve{1} = 13;                        // 13 nodes = 12 segments
Physical Curve("guide_wire") = {1};
