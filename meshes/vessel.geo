// Vessel centre-line for examples/guide_wire.toml (issue "a rod or wire inside a curved tube"):
// straight 20 mm along +x from the origin; bend 1: 60 deg, radius 50 mm, its plane lifted 10 deg
// out of x-y (towards +z); straight 10 mm; bend 2: 45 deg, radius 40 mm, towards +z. 2 mm segments.
// Regenerate the .msh with:  python meshes/generate.py vessel.geo
R1 = 0.05; a1 = Pi / 3; lift = 10 * Pi / 180;
R2 = 0.04; a2 = Pi / 4;
cl = Cos(lift); sl = Sin(lift);
Point(1) = {0, 0, 0, 1.0};
Point(2) = {0.02, 0, 0, 1.0};
Point(3) = {0.02, R1 * cl, R1 * sl, 1.0};                                    // centre of bend 1
x4 = 0.02 + R1 * Sin(a1); y4 = R1 * cl * (1 - Cos(a1)); z4 = R1 * sl * (1 - Cos(a1));
Point(4) = {x4, y4, z4, 1.0};
tx = Cos(a1); ty = Sin(a1) * cl; tz = Sin(a1) * sl;                          // tangent there
x5 = x4 + 0.01 * tx; y5 = y4 + 0.01 * ty; z5 = z4 + 0.01 * tz;
Point(5) = {x5, y5, z5, 1.0};
nm = Sqrt(1 - tz * tz);                                                      // m: +z made normal to t
mx = -tz * tx / nm; my = -tz * ty / nm; mz = (1 - tz * tz) / nm;
Point(6) = {x5 + R2 * mx, y5 + R2 * my, z5 + R2 * mz, 1.0};                  // centre of bend 2
Point(7) = {x5 + R2 * (Sin(a2) * tx + (1 - Cos(a2)) * mx),
            y5 + R2 * (Sin(a2) * ty + (1 - Cos(a2)) * my),
            z5 + R2 * (Sin(a2) * tz + (1 - Cos(a2)) * mz), 1.0};
Line(1) = {1, 2};
Circle(2) = {2, 3, 4};
Line(3) = {4, 5};
Circle(4) = {5, 6, 7};
Transfinite Curve{1} = 11;
Transfinite Curve{2} = 27;
Transfinite Curve{3} = 6;
Transfinite Curve{4} = 17;
Physical Curve("vessel") = {1, 2, 3, 4};
