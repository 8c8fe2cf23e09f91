// Example 1 rail (FORMULATION.md Part III §9): circular arc, radius 1 m, 90 deg opening
// symmetric about the lowest point (0,0,0); centre of curvature (0,0,1); vertical X-Z plane.
// From angle -45 deg to +45 deg about the lowest point, 16 equal segments (node 8 = lowest point).
// Regenerate the .msh with:  python meshes/generate.py
R = 1.0;
a = Pi / 4;
Point(1) = {-R * Sin(a), 0, R - R * Cos(a), 1.0};
Point(2) = {0, 0, R, 1.0};                       // centre (not meshed)
Point(3) = {R * Sin(a), 0, R - R * Cos(a), 1.0};
Circle(1) = {1, 2, 3};
Transfinite Curve{1} = 17;                        // 17 nodes = 16 segments
Physical Curve("rail") = {1};
