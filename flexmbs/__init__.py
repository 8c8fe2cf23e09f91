"""flexmbs: flexible multibody dynamics with ANCF beams and sliding joints with clearance.

Short public API (see DESIGN.md, "Python API")::

    import flexmbs as fm
    model = fm.Model(gravity=(0, 0, -9.81))
    beam = model.add_beam(fm.line((0, 0, 0), (1, 0, 0), elements=8),
                          section=fm.CircularSection(5e-3), material=fm.Material(E=2.1e11, rho=7800))
    model.clamp(beam.first_node)
    result = fm.simulate(model, t_end=1.0, dt=1e-3)
"""

from .constraints.sliding import SlidingJoint
from .contact.joint import CircleHole, Hole, SlidingClearanceJoint, SuperellipseHole
from .contact.laws import Hertz, HuntCrossley, LankaraniNikravesh, LinearPenalty, RegularizedCoulomb
from .elements.ancf_cable import CableOptions
from .errors import (
    ConvergenceError,
    FlexmbsError,
    GeometryError,
    ModelError,
    RedundantConstraintError,
    ScenarioError,
    SimulationStopped,
)
from .geometry.curves import Centerline, arc, line, polyline
from .loads import Constant, Function, HalfSine, Ramp, Sine, Table, TimeFunction
from .model import GROUND, Beam, Model, Node, Pose, RigidBody
from .sections import BeamStiffness, CircularSection, Material
from .simulation import Result, modes, simulate, solve_static
from .solvers.generalized_alpha import GeneralizedAlpha
from .solvers.newton import NewtonOptions
from .solvers.static import StaticOptions
from .sweeps import sweep


def read_curve(path, **kwargs):  # noqa: ANN001, ANN201 - thin lazy wrapper (meshio import cost)
    """Read a beam centreline from a mesh file (gmsh .msh, .vtu, ...); see geometry.mesh_input."""
    from .geometry.mesh_input import read_curve as _read_curve

    return _read_curve(path, **kwargs)


from ._version import __version__  # noqa: E402 - after the API imports, as before

__all__ = [
    "CircleHole", "Hole", "SlidingClearanceJoint", "SuperellipseHole", "Hertz", "HuntCrossley",
    "LankaraniNikravesh", "LinearPenalty", "RegularizedCoulomb",
    "Beam", "BeamStiffness", "CableOptions", "Centerline", "CircularSection", "Constant",
    "ConvergenceError", "FlexmbsError", "Function", "GROUND", "GeneralizedAlpha", "GeometryError",
    "HalfSine", "Material", "Model", "ModelError", "NewtonOptions", "Node", "Pose", "Ramp",
    "RedundantConstraintError", "Result", "RigidBody", "ScenarioError", "SimulationStopped",
    "Sine", "SlidingJoint", "StaticOptions", "Table", "TimeFunction", "__version__", "arc", "line",
    "modes", "polyline", "read_curve", "simulate", "solve_static", "sweep",
]
