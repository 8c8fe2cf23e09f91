// Example 2 guide wire (FORMULATION.md Part III §10): straight, anchors G0=(-0.1, -e+dy, 0) and
// G1=(2h+0.1, -e+dy, 0) with h=0.5 m, e=0.02 m, dy=5 mm -> y = -0.015 m; L_w = 1.2 m, 12 segments.
// Regenerate the .msh with:  python meshes/generate.py
y = -0.02 + 0.005;
Point(1) = {-0.1, y, 0, 1.0};
Point(2) = {1.1, y, 0, 1.0};
Line(1) = {1, 2};
Transfinite Curve{1} = 13;                        // 13 nodes = 12 segments
Physical Curve("guide_wire") = {1};
