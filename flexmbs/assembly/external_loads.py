"""The model's external loads sorted for their owners: gravity and constant forces as one
vector, timed forces, the rigid bodies' loads, the moments on beam nodes."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import ModelError
from ..loads import Constant, TimeFunction
from ..model import Beam, Model, Node, RigidBody
from .numbering import Numbering


class ExternalLoads(NamedTuple):
    gravity_vector: np.ndarray   # (n_coords,) the gravity force (its potential energy)
    f_const: np.ndarray          # (n_coords,) gravity and the loads of constant function 1
    timed: list[tuple[np.ndarray, np.ndarray, TimeFunction]]      # (coordinates, values, f(t))
    body_loads: list[tuple[RigidBody, np.ndarray | None, np.ndarray, np.ndarray | None, TimeFunction]]
    node_moments: list[tuple[np.ndarray, int, np.ndarray, np.ndarray, TimeFunction]]


def collect_loads(model: Model, numbering: Numbering) -> ExternalLoads:
    """Gravity on every element and body, and every load of the model in the form its owner
    packs (:func:`flexmbs.loads.pack_loads`, :func:`flexmbs.elements.rigid_body.pack_bodies`)."""
    n = numbering.n_coords
    g = model.gravity
    f_const = np.zeros(n)
    gravity_vector = np.zeros(n)
    for spec in numbering.groups:
        np.add.at(gravity_vector, spec.dofs, spec.element_type.gravity_force(spec.props, g))
    for body in model.bodies:
        d = numbering.body_dofs(body)
        gravity_vector[d[:3]] += body.mass * g
    f_const += gravity_vector
    timed: list[tuple[np.ndarray, np.ndarray, TimeFunction]] = []
    body_loads: list[tuple[RigidBody, np.ndarray | None, np.ndarray, np.ndarray | None,
                           TimeFunction]] = []
    moments: list[tuple[np.ndarray, int, np.ndarray, np.ndarray, TimeFunction]] = []
    for load in model.loads:
        idx: np.ndarray
        vals: np.ndarray
        if load.kind == "distributed":
            beam: Beam = load.target  # type: ignore[assignment]
            gi, sl = numbering.beam_slices[id(beam)]
            spec = numbering.groups[gi]
            props = type(spec.props)(*[np.asarray(a)[sl] for a in spec.props])
            Q = spec.element_type.distributed_force(props, load.force)
            idx, vals = spec.dofs[sl].ravel(), Q.ravel()
        elif isinstance(load.target, RigidBody):
            body_loads.append((load.target, load.point, load.force, load.moment,
                               load.function))
            continue
        else:
            if isinstance(load.target, Node):
                node = load.target
                beam, s = node.beam, None
            else:
                beam, s = load.target  # type: ignore[misc]
            if s is None:
                d = numbering.node_dofs(node)
                lay = node.beam.layout
                idx, vals = d[list(lay.position)], load.force.copy()
                if load.moment is not None:
                    # a moment on a node works through its current slope (and twist):
                    # loads.node_moment (docs/theory.md §I.1.2, §I.2.3); the base tangent t̄ of
                    # the twist is the node's reference tangent
                    slope = d[list(lay.slope)]
                    t = numbering.q_ref[slope] / np.linalg.norm(numbering.q_ref[slope])
                    moments.append((slope, -1 if lay.twist is None else d[lay.twist],
                                    load.moment, t, load.function))
            else:
                e, xi = beam.locate(float(s))
                dofs = numbering.element_dofs(beam)[e]
                L = np.array([beam.centerline.lengths[e]])
                Q = beam.element_type.point_force(np.array([xi]), L, load.force[None, :])[0]
                if load.moment is not None:
                    raise ModelError(f"load '{load.name}': moments are supported at nodes only")
                idx, vals = dofs, Q
        fn = load.function
        if isinstance(fn, Constant) and fn.value == 1.0:
            np.add.at(f_const, idx, vals)
        else:
            timed.append((idx, vals, fn))
    return ExternalLoads(gravity_vector, f_const, timed, body_loads, moments)
