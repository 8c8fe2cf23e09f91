"""flexmbs: flexible multibody dynamics with ANCF beams and sliding joints with clearance.

Short public API (the docs site's "API reference" and "Getting started" pages; docs/design.md,
"Python API")::

    import flexmbs as fm
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=8),
                          section=fm.CircularSection(5e-3), material=fm.Material(E=2.1e11, rho=7800))
    model.clamp(beam.first_node)
    result = fm.simulate(model, t_end=1.0, dt=1e-3)
"""

from typing import TYPE_CHECKING, Any

from .errors import (
    ConvergenceError,
    FlexmbsError,
    GeometryError,
    ModelError,
    RedundantConstraintError,
    ScenarioError,
    SimulationStopped,
)

# The public names are imported on first use (PEP 562): ``import flexmbs`` and the ``flexmbs``
# command start in milliseconds (numpy, scipy and numba load when a model is built), and a
# Ctrl-C during start-up meets the command's own handler, not an import traceback.
if TYPE_CHECKING:  # pragma: no cover - for type checkers; the same names as _LAZY
    from .beam_sections import BeamStiffness, CircularSection, Material
    from .constraints.sliding import SlidingJoint
    from .contact.joint import CircleHole, CurvedBore, Hole, SlidingClearanceJoint, SuperellipseHole
    from .contact.laws import (
        Friction,
        Hertz,
        HuntCrossley,
        LankaraniNikravesh,
        LinearPenalty,
        RegularizedCoulomb,
    )
    from .contact.tube_joint import TubeJoint
    from .elements.ancf_cable import CableOptions
    from .geometry.curves import Centerline, arc, line, polyline
    from .loads import Constant, Function, HalfSine, Moves, Ramp, Sine, Table, TimeFunction
    from .model import GROUND, Beam, Model, Node, Pose, RigidBody
    from .ropes import Rope
    from .simulation import Result, modes, simulate, solve_quasi_static, solve_static
    from .solvers.generalized_alpha import GeneralizedAlpha
    from .solvers.newton import NewtonOptions
    from .solvers.static import StaticOptions
    from .sweeps import sweep
    from .tendons import Tendon, TendonParts

_LAZY = {
    "SlidingJoint": ".constraints.sliding",
    "CircleHole": ".contact.joint",
    "CurvedBore": ".contact.joint",
    "Hole": ".contact.joint",
    "SlidingClearanceJoint": ".contact.joint",
    "SuperellipseHole": ".contact.joint",
    "TubeJoint": ".contact.tube_joint",
    "Friction": ".contact.laws",
    "Hertz": ".contact.laws",
    "HuntCrossley": ".contact.laws",
    "LankaraniNikravesh": ".contact.laws",
    "LinearPenalty": ".contact.laws",
    "RegularizedCoulomb": ".contact.laws",
    "CableOptions": ".elements.ancf_cable",
    "Centerline": ".geometry.curves",
    "arc": ".geometry.curves",
    "line": ".geometry.curves",
    "polyline": ".geometry.curves",
    "Constant": ".loads",
    "Function": ".loads",
    "HalfSine": ".loads",
    "Moves": ".loads",
    "Ramp": ".loads",
    "Sine": ".loads",
    "Table": ".loads",
    "TimeFunction": ".loads",
    "GROUND": ".model",
    "Beam": ".model",
    "Model": ".model",
    "Node": ".model",
    "Pose": ".model",
    "RigidBody": ".model",
    "Rope": ".ropes",
    "BeamStiffness": ".beam_sections",
    "CircularSection": ".beam_sections",
    "Material": ".beam_sections",
    "Result": ".simulation",
    "modes": ".simulation",
    "simulate": ".simulation",
    "solve_static": ".simulation",
    "solve_quasi_static": ".simulation",
    "GeneralizedAlpha": ".solvers.generalized_alpha",
    "NewtonOptions": ".solvers.newton",
    "StaticOptions": ".solvers.static",
    "sweep": ".sweeps",
    "Tendon": ".tendons",
    "TendonParts": ".tendons",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'flexmbs' has no attribute '{name}'")
    import importlib

    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


def read_curve(path, **kwargs):
    """Read a beam centreline from a mesh file (gmsh .msh, .vtu, ...); see geometry.mesh_input.

    Parameters
    ----------
    path : str or os.PathLike
        The mesh file (any format meshio reads).
    **kwargs
        ``group`` (gmsh physical curve name), ``elements`` (resample to that many equal
        elements), ``tangents_field`` (point data to use as tangents); see
        :func:`flexmbs.geometry.mesh_input.read_curve`.

    Returns
    -------
    Centerline
        The curve's nodes, tangents and element lengths.
    """
    from .geometry.mesh_input import read_curve as _read_curve

    return _read_curve(path, **kwargs)


from ._version import __version__  # noqa: E402 - after the API imports, as before

__all__ = [
    "CircleHole", "CurvedBore", "Hole", "SlidingClearanceJoint", "SuperellipseHole", "Friction",
    "Hertz", "HuntCrossley",
    "LankaraniNikravesh", "LinearPenalty", "RegularizedCoulomb",
    "Beam", "BeamStiffness", "CableOptions", "Centerline", "CircularSection", "Constant",
    "ConvergenceError", "FlexmbsError", "Function", "GROUND", "GeneralizedAlpha", "GeometryError",
    "HalfSine", "Material", "Model", "ModelError", "Moves", "NewtonOptions", "Node", "Pose", "Ramp",
    "RedundantConstraintError", "Result", "RigidBody", "Rope", "ScenarioError", "SimulationStopped",
    "Sine", "SlidingJoint", "StaticOptions", "Table", "TimeFunction", "__version__", "arc", "line",
    "modes", "polyline", "read_curve", "simulate", "solve_quasi_static", "solve_static", "sweep",
    "Tendon", "TendonParts", "TubeJoint",
]
