"""The numbers compiled kernels and Python agree on come from one table each (issue 54, item 2):
every ``ERR_*`` and ``SHAPE_*`` constant of the package is a value of ``flexmbs.codes``, no two
owners share an error code, and every compiled hole section is dispatched (an unknown code is
never silently another shape)."""

from __future__ import annotations

import importlib
import pkgutil
import re

import numpy as np
import pytest

import flexmbs
from flexmbs import codes, driver
from flexmbs.contact.shapes import HOLE_SECTIONS, CircleSection, section_boundary, section_contains
from flexmbs.errors import ModelError


def _constants(prefix: str) -> dict[str, int]:
    """Every module-level ``PREFIX*`` integer of the package, by module.name (re-exports once)."""
    found: dict[str, int] = {}
    owners: dict[tuple[str, int], str] = {}
    for info in pkgutil.walk_packages(flexmbs.__path__, "flexmbs."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if re.fullmatch(prefix + r"[A-Z_]+", name) and isinstance(value, int) \
                    and not isinstance(value, bool):
                owners.setdefault((name, value), f"{info.name}.{name}")
    for (_name, value), where in owners.items():
        found[where] = value
    return found


def _polygon_distance(n: int, apothem: float, y: float, z: float) -> float:
    """Distance of (y, z) outside the regular n-gon of ``apothem`` whose first flat faces +y:
    the nearest of its sides as segments between its vertices."""
    corners = [apothem / np.cos(np.pi / n) * np.array([np.cos((2 * k + 1) * np.pi / n),
                                                        np.sin((2 * k + 1) * np.pi / n)])
               for k in range(n)]
    p = np.array([y, z])
    best = np.inf
    for k in range(n):
        a, b = corners[k - 1], corners[k]
        u = float(np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0))
        best = min(best, float(np.linalg.norm(p - a - u * (b - a))))
    return best


def test_every_error_code_comes_from_the_table_and_means_one_thing() -> None:
    errors = _constants("ERR_")
    assert len(errors) >= 8
    table = set(codes.ERROR_CODES.values())
    assert set(errors.values()) <= table, errors
    by_value: dict[int, set[str]] = {}
    for where, value in errors.items():
        by_value.setdefault(value, set()).add(where.rsplit(".", 1)[1])
    assert all(len(names) == 1 for names in by_value.values()), by_value
    kinds = [code for kind in driver.INTERACTION_KINDS for code in kind.errors]
    assert len(kinds) == len(set(kinds)) == len(driver.KIND_OF_ERROR)


def test_a_code_given_twice_is_refused() -> None:
    with pytest.raises(ValueError, match="error code 3 given to both 'a' and 'b'"):
        codes._unique("error", {"a": 3, "b": 3})


def test_every_compiled_section_is_dispatched_and_an_unknown_code_is_not_a_shape() -> None:
    shapes = _constants("SHAPE_")
    shapes = {k: v for k, v in shapes.items() if not k.endswith("SHAPE_SAMPLES")}
    assert set(shapes.values()) == set(codes.SHAPE_CODES.values())
    on_wall = {   # each shape's wall in closed form (not through its kernels)
        "circle": ({"radius": 1e-3}, lambda y, z: np.hypot(y, z) / 1e-3 - 1.0),
        "superellipse": ({"a": 2e-3, "b": 1e-3, "exponent": 4.0},
                         lambda y, z: (abs(y) / 2e-3) ** 4 + (abs(z) / 1e-3) ** 4 - 1.0),
        "rounded_rectangle": ({"w": 3e-3, "h": 2e-3, "r": 4e-4},
                              lambda y, z: np.hypot(max(abs(y) - 2.6e-3, 0.0),
                                                    max(abs(z) - 1.6e-3, 0.0)) / 4e-4 - 1.0
                              if abs(y) > 2.6e-3 and abs(z) > 1.6e-3
                              else max(abs(y) / 3e-3, abs(z) / 2e-3) - 1.0),
        "rounded_polygon": ({"sides": 6, "apothem": 3e-3, "r": 8e-4},
                            lambda y, z: _polygon_distance(6, 3e-3 - 8e-4, y, z) / 8e-4 - 1.0)}
    assert set(on_wall) == set(HOLE_SECTIONS.names()) == set(codes.SHAPE_CODES)
    Y, Yp, Ypp = np.zeros(2), np.zeros(2), np.zeros(2)
    for name, (params, wall) in on_wall.items():
        section = HOLE_SECTIONS.get(name)(**params)
        kind, p = section.compiled_shape()
        assert kind == codes.SHAPE_CODES[name]
        for psi in np.linspace(0.0, 2 * np.pi, 13):
            section_boundary(kind, p, psi, Y, Yp, Ypp)
            assert abs(wall(*Y)) < 1e-9, (name, psi, Y)
            assert section_contains(kind, p, *(Y * (1 - 1e-6)))
            assert not section_contains(kind, p, *(Y * (1 + 1e-6)))
    unknown = max(codes.SHAPE_CODES.values()) + 1
    section_boundary(unknown, np.ones(4), 0.3, Y, Yp, Ypp)
    assert np.isnan(Y).all() and np.isnan(Yp).all() and np.isnan(Ypp).all()
    assert not section_contains(unknown, np.ones(4), 0.0, 0.0)


def test_a_section_with_an_unlisted_code_is_refused_by_the_joint() -> None:
    import flexmbs as fm

    class Odd(CircleSection):
        def compiled_shape(self):
            return 99, np.zeros(4)

    model = fm.Model()
    wire = model.add_beam(fm.line((0, 0, 0), (0.1, 0, 0), elements=2),
                          section=fm.CircularSection(1e-4), material=fm.Material(E=2e11, rho=7800))
    body = model.add_rigid_body(mass=1.0, inertia=(1, 1, 1), name="tube")
    with pytest.raises(ModelError, match="compiled shape code 99.*SHAPE_CODES"):
        fm.SlidingClearanceJoint(wire, body, hole=fm.Hole(Odd(2e-4), 0.01, 3),
                                 contact=fm.LinearPenalty(stiffness=1e5))
