"""Exceptions of flexmbs. Every message should tell the user what is wrong and how to fix it."""

from __future__ import annotations


class FlexmbsError(Exception):
    """Base class of all flexmbs errors (the CLI prints these as one line)."""


class ModelError(FlexmbsError):
    """The model is inconsistent (unknown names, redundant constraints, bad sizes...)."""


class GeometryError(FlexmbsError):
    """A curve, mesh or section cannot be used as given."""


class ScenarioError(FlexmbsError):
    """A scenario file or override is invalid; the message names the key path."""


class ConvergenceError(FlexmbsError):
    """A nonlinear solve failed; the message names the worst equation and its object."""


class OffPlanError(ConvergenceError):
    """A joint's Jacobian fell outside the elements the factorisation's plan follows it on
    (:meth:`flexmbs.assembly.Assembly.follow`): the solve is to be re-planned and repeated, not
    shortened. ``widen`` = (error code, window row, element) for
    :meth:`~flexmbs.assembly.Assembly.contact_windows`."""

    def __init__(self, message: str, widen: tuple[int, int, int]) -> None:
        super().__init__(message)
        self.widen = widen


class RedundantConstraintError(ModelError):
    """The constraint Jacobian is rank deficient; the message lists the dependent equations."""


class FlexmbsWarning(UserWarning):
    """Something that runs but is probably not what was meant (printed as one line by the
    CLI), e.g. a clearance joint starting with the beam pressed into the bore wall."""


class Interrupted(KeyboardInterrupt):
    """A termination signal (SIGTERM, SIGHUP) handled like Ctrl-C: the run finishes its frame,
    writes its checkpoint and ``summary.json`` (status ``interrupted: <signal>``)."""


class SimulationStopped(FlexmbsError):
    """The simulation cannot continue (e.g. a sliding body reached the end of its beam); the
    steps before stand."""
