"""flexmbs.registry: one Registry class; the Python API and the scenario reader share each one."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

from flexmbs.contact import laws, sections
from flexmbs.errors import ModelError, ScenarioError
from flexmbs.io.builders import CONSTRAINTS, ELEMENTS, JOINTS, LOADS, PROBES, SPRINGS
from flexmbs.io.scenario import load_scenario
from flexmbs.registry import Registry

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SLEEVE = EXAMPLES / "curved_beam_sleeve.toml"


def _shape(value: str) -> str:
    return f"joints.sleeve.hole={value}"


def test_get_register_names_contains() -> None:
    reg: Registry[int] = Registry("gadget")
    assert reg.register("one", 1) == 1

    @reg.register("two")
    def two() -> int:
        return 2

    assert reg.get("two") is two and reg.names() == ("one", "two") and list(reg) == ["one", "two"]
    assert "one" in reg and "three" not in reg and len(reg) == 2
    with pytest.raises(ModelError, match=r"^unknown gadget 'three' \(known: one, two\)$"):
        reg.get("three")
    assert reg.unregister("one") == 1 and reg.names() == ("two",)


def test_duplicate_and_bad_names_are_rejected() -> None:
    reg: Registry[int] = Registry("gadget")
    reg.register("one", 1)
    with pytest.raises(ModelError, match="gadget 'one' is already registered"):
        reg.register("one", 2)
    assert reg.get("one") == 1
    for bad in ("", " one"):
        with pytest.raises(ModelError, match="gadget name must be a non-empty string"):
            reg.register(bad, 3)


def test_the_registries_hold_the_documented_names() -> None:
    assert sections.HOLE_SECTIONS.names() == ("circle", "rounded_polygon", "rounded_rectangle",
                                              "superellipse")
    assert set(laws.CONTACT_LAWS) == {"linear", "hertz", "hunt_crossley", "lankarani_nikravesh"}
    assert sections.SECTION_TYPES is sections.HOLE_SECTIONS and laws.LAWS is laws.CONTACT_LAWS
    assert ELEMENTS.names()[0] == "ancf_cable"
    assert JOINTS.names() == ("sliding", "sliding_clearance", "rope", "tube")
    assert CONSTRAINTS.names() == ("clamp", "pin", "fix_body", "spherical", "revolute", "prismatic",
                                   "rigid", "prescribed", "joint", "driver")
    assert LOADS.names() == ("point", "distributed")
    assert SPRINGS.names() == ("translational", "rotational")
    assert set(PROBES) == {"beam_point", "body_position", "body_orientation", "body_point",
                           "energy", "slide_coordinate", "contact_force", "rope", "joint_reaction",
                           "reaction", "tendon_tension", "tendon_displacement"}


def test_scenario_and_python_fail_with_the_same_message() -> None:
    """An unknown hole shape or contact law: the registry's message, after the key path."""
    for value, key, python in (
            ('{ shape = "hexagon", length = 0.04 }', "joints[sleeve].hole.shape",
             lambda: sections.get_section("hexagon")),
            ('"spring"', "joints[sleeve].contact.law", lambda: laws.get_law("spring"))):
        with pytest.raises(ModelError) as py:
            python()
        override = _shape(value) if "shape" in value else f"joints.sleeve.contact.law={value}"
        with pytest.raises(ScenarioError) as sc:
            load_scenario(SLEEVE, [override])
        assert str(sc.value) == f"{key}: {py.value}"


def test_superellipse_keys_are_the_python_parameters() -> None:
    sc = load_scenario(SLEEVE, [_shape('{ shape = "superellipse", a = 2.6e-3, b = 2.5e-3, '
                                       'exponent = 4, length = 0.04, sections = 5 }')])
    (joint,) = sc.model.interactions
    assert joint.hole.section == sections.get_section("superellipse", a=2.6e-3, b=2.5e-3,
                                                      exponent=4.0)
    assert joint.hole.section == sections.SuperellipseSection(a=2.6e-3, b=2.5e-3, exponent=4.0)
    with pytest.raises(ScenarioError, match=r"joints\[sleeve\]\.hole\.semi_axes: renamed; give "
                                            "the semi-axes as a = "):
        load_scenario(SLEEVE, [_shape('{ shape = "superellipse", semi_axes = [2.6e-3, 2.5e-3], '
                                      'length = 0.04 }')])
    with pytest.raises(ScenarioError, match=r"joints\[sleeve\]\.hole\.b: missing required key"):
        load_scenario(SLEEVE, [_shape('{ shape = "superellipse", a = 2.6e-3, length = 0.04 }')])
    with pytest.raises(ScenarioError, match=r"^joints\[sleeve\]\.hole\.exponent: expected a "
                                            "number >= 2, got 1.5"):
        load_scenario(SLEEVE, [_shape('{ shape = "superellipse", a = 2.6e-3, b = 2.6e-3, '
                                      'exponent = 1.5, length = 0.04 }')])


@dataclass(frozen=True)
class _ScaledCircle(sections.CircleSection):
    """A plug-in shape for the test: a circle of radius ``radius * scale``."""

    scale: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", self.radius * self.scale)
        super().__post_init__()


def test_a_registered_shape_is_a_scenario_shape_without_scenario_code() -> None:
    sections.HOLE_SECTIONS.register("scaled_circle", _ScaledCircle)
    try:
        assert sections.get_section("scaled_circle", radius=1.0, scale=2.0).radius == 2.0
        sc = load_scenario(SLEEVE, [_shape('{ shape = "scaled_circle", radius = 1.25e-3, '
                                           'scale = 2.0, length = 0.04, sections = 3 }')])
        (joint,) = sc.model.interactions
        assert isinstance(joint.hole.section, _ScaledCircle)
        assert joint.hole.section.radius == pytest.approx(2.5e-3)
        with pytest.raises(ScenarioError, match=r"unknown key 'diameter' in joints\[sleeve\]\.hole "
                                                r"\(allowed: length, open_ends, path, point, "
                                                r"radius, scale, "):
            load_scenario(SLEEVE, [_shape('{ shape = "scaled_circle", diameter = 1.0, '
                                          'length = 0.04 }')])
    finally:
        sections.HOLE_SECTIONS.unregister("scaled_circle")
    assert "scaled_circle" not in sections.HOLE_SECTIONS
