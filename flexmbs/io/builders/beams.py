"""``[[beams]]``: the element registry, centreline geometry and cross-section of a beam.

``element = "<name>"`` selects the builder in :data:`ELEMENTS` (default ``"ancf_cable"``); the
builder reads the element's own keys, the shared ones (:data:`BEAM_KEYS`) through
:func:`read_geometry` and :func:`read_stiffness`, and adds the beam to the model.
"""

from __future__ import annotations

import math
from contextlib import nullcontext
from dataclasses import replace

import numpy as np

from ...beam_sections import BeamStiffness, CircularSection, Material
from ...elements.ancf_cable import CableOptions
from ...errors import ScenarioError
from ...geometry.curves import Centerline, arc, line, polyline
from ...model import Beam
from ...registry import Registry
from ..tables import Table, at, display_path, is_number
from .context import BuildContext, Builder

__all__ = ["BEAM_KEYS", "ELEMENTS", "build_beam", "read_geometry", "read_stiffness"]

#: ``element = ...`` -> builder(table, ctx) -> Beam
ELEMENTS: Registry[Builder] = Registry("element")

_MATERIAL_KEYS = ("youngs_modulus", "density", "poisson_ratio", "shear_modulus")
_EXPLICIT_KEYS = ("axial_stiffness", "bending_stiffness", "mass_per_length", "torsional_stiffness")
#: keys of every beam, whatever its element
BEAM_KEYS = ("name", "geometry", "elements", "element", "radius", *_MATERIAL_KEYS, *_EXPLICIT_KEYS,
             "damping", "reference_axial_strain", "stress_free")


def build_beam(t: Table, ctx: BuildContext) -> Beam:
    """A ``[[beams]]`` entry, built by the builder of its ``element``."""
    _, build = t.lookup("element", ELEMENTS, "ancf_cable")
    beam: Beam = build(t, ctx)
    return beam


@ELEMENTS.register("ancf_cable")
def _ancf_cable(t: Table, ctx: BuildContext) -> Beam:
    """12-DOF ANCF cable (no torsion); its options are the keys of :class:`CableOptions`."""
    t.allow((*BEAM_KEYS, "bending", "axial_rule", "bending_points", "exudyn_compatible"))
    centerline, stiffness = _geometry_and_section(t, ctx)
    options = CableOptions(bending=t.choice("bending", ("vector", "scalar"), "vector"),
                           axial_rule=t.choice("axial_rule", ("lobatto3", "gauss5"), "lobatto3"),
                           bending_points=t.integer("bending_points", 3, ge=2, le=3),
                           exudyn_compatible=t.boolean("exudyn_compatible", False))
    return _add(t, ctx, centerline, stiffness, element="ancf_cable", options=options)


@ELEMENTS.register("ancf_rod14")
def _ancf_rod14(t: Table, ctx: BuildContext) -> Beam:
    """14-DOF ANCF rod with a nodal twist (torsion-capable): the section's torsional stiffness
    from ``shear_modulus``/``poisson_ratio`` (with radius + youngs_modulus) or an explicit
    ``torsional_stiffness``; ``twist_inertia`` ρJ_p [kg m] optional with an explicit section."""
    t.allow((*BEAM_KEYS, "twist_inertia"))
    if t.has("stress_free"):
        raise ScenarioError(f"{t.key('stress_free')}: element 'ancf_rod14' takes its twist charts "
                            "from one shape: give its stress-free shape as the geometry (or use "
                            "element = \"ancf_cable\")")
    centerline, stiffness = _geometry_and_section(t, ctx)
    if stiffness.torsional_stiffness is None:
        raise ScenarioError(f"{t.key('torsional_stiffness')}: missing: element 'ancf_rod14' "
                            "carries torsion; give torsional_stiffness [N m^2] with an explicit "
                            "section (or radius + youngs_modulus + density + poisson_ratio)")
    if t.has("twist_inertia"):
        if not t.has("axial_stiffness"):
            raise ScenarioError(f"{t.key('twist_inertia')}: only with an explicit section; with "
                                "radius + density it is density * pi r^4/2")
        stiffness = replace(stiffness, twist_inertia=t.number("twist_inertia", gt=0, unit="kg m"))
    return _add(t, ctx, centerline, stiffness, element="ancf_rod14", options=None)


def _geometry_and_section(t: Table, ctx: BuildContext) -> tuple[Centerline, BeamStiffness]:
    elements = t.integer("elements", None, ge=1)
    return read_geometry(ctx, t.table("geometry"), elements, t), read_stiffness(t)


def _add(t: Table, ctx: BuildContext, centerline: Centerline, stiffness: BeamStiffness, *,
         element: str, options: CableOptions | None) -> Beam:
    """The beam into the model; ``stress_free = { line | arc | polyline | mesh }`` (the same
    grammar as ``geometry``): the shape it is stress-free in when it starts on another."""
    free = None
    if t.has("stress_free"):
        free = read_geometry(ctx, t.table("stress_free"), t.integer("elements", None, ge=1), t)
    damping = t.number("damping", 0.0, ge=0, unit="s")
    eps0 = t.number("reference_axial_strain", 0.0, gt=-1, lt=1, unit="1")
    with at(t.key("stress_free")) if free is not None else nullcontext():
        return ctx.model.add_beam(centerline, section=stiffness, name=t.raw["name"],
                                  options=options, damping=damping, reference_axial_strain=eps0,
                                  element=element, stress_free=free)


def read_geometry(ctx: BuildContext, g: Table, elements: int | None, beam: Table) -> Centerline:
    """The centreline of ``geometry = { line | arc | polyline | mesh }``."""
    g.allow(("line", "arc", "mesh", "group", "polyline"))
    kinds = g.present(("line", "arc", "mesh", "polyline"))
    if len(kinds) != 1:
        raise ScenarioError(f"{g.path}: expected exactly one of 'line', 'arc', 'mesh', 'polyline'"
                            f", got {', '.join(kinds) or 'none'}")
    kind = kinds[0]
    if g.has("group") and kind != "mesh":
        raise ScenarioError(f"{g.key('group')}: 'group' selects a curve of a mesh file; it needs "
                            "geometry.mesh")
    if kind in ("line", "arc") and elements is None:
        raise ScenarioError(f"{beam.key('elements')}: missing required key (expected an integer "
                            f">= 1; a {kind} geometry needs the number of elements)")
    if kind == "mesh":
        file = ctx.resolve(g.string("mesh"))
        group = g.string("group", None)
        if not file.exists():
            raise ScenarioError(f"{g.key('mesh')}: mesh file not found: {display_path(file)}")
        if file.is_dir():
            raise ScenarioError(f"{g.key('mesh')}: {display_path(file)} is a folder; give a "
                                "mesh file (.msh, .vtu, .vtk, ...)")
        if not file.is_file():
            raise ScenarioError(f"{g.key('mesh')}: {display_path(file)} is not a regular file "
                                "(a device or a pipe); give a mesh file (.msh, .vtu, .vtk, ...)")
        with at(g.key("mesh")):
            from ...geometry.mesh_input import read_curve

            return read_curve(file, group=group, elements=elements)
    sub = g.table(kind)
    with at(sub.path):
        if kind == "line":
            assert elements is not None  # checked above
            sub.allow(("start", "end"))
            return line(sub.vector("start", unit="m"), sub.vector("end", unit="m"), elements=elements)
        if kind == "arc":
            assert elements is not None
            sub.allow(("center", "radius", "start", "angle", "normal"))
            return arc(sub.vector("center", unit="m"), sub.number("radius", gt=0, unit="m"),
                       sub.vector("start", unit="m"), sub.number("angle", unit="rad"),
                       sub.vector("normal", np.array([0.0, 0.0, 1.0]), unit="1"),
                       elements=elements)
        sub.allow(("points", "tangents", "closed"))
        pts = _points(sub, "points")
        tans = _points(sub, "tangents", len(pts)) if sub.has("tangents") else None
        return polyline(pts, tans, closed=sub.boolean("closed", False), elements=elements)


def _points(t: Table, k: str, n: int | None = None) -> np.ndarray:
    v = t.get(k, expected="an array of points [[x, y, z], ...]")
    ok = (isinstance(v, list) and len(v) >= (n or 2) and (n is None or len(v) == n)
          and all(isinstance(p, list) and len(p) == 3
                  and all(is_number(x) and math.isfinite(x) for x in p) for p in v))
    if not ok:
        raise t.fail(k, f"an array of {n or 'at least 2'} points [[x, y, z], ...]", v)
    return np.array(v, dtype=float)


def read_stiffness(t: Table) -> BeamStiffness:
    """The section: radius + youngs_modulus + density (+ poisson_ratio | shear_modulus), or
    explicit axial_stiffness + bending_stiffness + mass_per_length (+ torsional_stiffness)."""
    explicit = t.present(_EXPLICIT_KEYS[:3])
    if explicit:
        mixed = t.present(_MATERIAL_KEYS)
        if mixed:
            raise ScenarioError(f"{t.path}: give the section either as radius + youngs_modulus + "
                                "density or as axial_stiffness + bending_stiffness + "
                                f"mass_per_length, not both (got {', '.join(explicit + mixed)})")
        return BeamStiffness(axial_stiffness=t.number("axial_stiffness", gt=0, unit="N"),
                             bending_stiffness=t.number("bending_stiffness", gt=0, unit="N m^2"),
                             mass_per_length=t.number("mass_per_length", ge=0, unit="kg/m"),
                             torsional_stiffness=t.number("torsional_stiffness", None, gt=0, unit="N m^2"),
                             radius=t.number("radius", None, gt=0, unit="m"))
    if t.has("torsional_stiffness"):
        raise ScenarioError(f"{t.key('torsional_stiffness')}: only with an explicit section "
                            "(axial_stiffness, bending_stiffness, mass_per_length); with "
                            "radius + youngs_modulus it follows from shear_modulus/poisson_ratio")
    if not t.has("radius") and not t.has("youngs_modulus"):
        raise ScenarioError(f"{t.path}: missing section: give radius + youngs_modulus + density "
                            "or axial_stiffness + bending_stiffness + mass_per_length")
    radius = t.number("radius", gt=0, unit="m")
    E = t.number("youngs_modulus", gt=0, unit="Pa")
    rho = t.number("density", ge=0, unit="kg/m^3")
    t.exclusive("poisson_ratio", "shear_modulus")
    if t.has("shear_modulus"):
        G = t.number("shear_modulus", gt=0, unit="Pa")
        nu = E / (2 * G) - 1
        if not -1 < nu < 0.5:
            raise t.fail("shear_modulus", f"a number > {E / 3:g} (youngs_modulus/3, so that the "
                         "Poisson ratio E/2G - 1 is in (-1, 0.5))", G)
    else:
        nu = t.number("poisson_ratio", 0.3, gt=-1, lt=0.5, unit="1")
    return BeamStiffness.from_section(CircularSection(radius), Material(E=E, rho=rho, nu=nu))
