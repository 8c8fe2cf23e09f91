"""Scenario builders, one module per kind, each kind a :class:`~flexmbs.registry.Registry` of
``builder(table, ctx) -> object`` (see :mod:`.context`):

==============  ===================  ======================================================
kind            registry             module
==============  ===================  ======================================================
element         :data:`ELEMENTS`     :mod:`.beams` (``[[beams]] element = ...``)
constraint      :data:`CONSTRAINTS`  :mod:`.constraints`
joint           :data:`JOINTS`       :mod:`.joints` (hole sections and contact laws: the
                                     registries of :mod:`flexmbs.contact`)
load            :data:`LOADS`        :mod:`.loads` (also time functions)
probe           :data:`PROBES`       :mod:`.probes`
spring          :data:`SPRINGS`      :mod:`.springs` (``[[springs]] type = ...``)
==============  ===================  ======================================================

Rigid bodies (:mod:`.bodies`), tendons (:mod:`.tendons`) and the ``[simulation]`` table
(:mod:`.simulation`) have one form each and no registry. Importing this package registers every
built-in builder.
"""

from .beams import ELEMENTS, build_beam
from .bodies import build_rigid_body
from .constraints import CONSTRAINTS
from .context import BuildContext, Builder, build_entry
from .joints import JOINTS
from .loads import LOADS
from .probes import PROBES, build_probe
from .simulation import INTEGRATORS, SimulationSettings, read_simulation
from .springs import SPRINGS
from .tendons import build_tendon

__all__ = ["CONSTRAINTS", "ELEMENTS", "INTEGRATORS", "JOINTS", "LOADS", "PROBES", "SPRINGS", "Builder",
           "BuildContext", "SimulationSettings", "build_beam", "build_entry", "build_probe",
           "build_rigid_body", "build_tendon", "read_simulation"]
