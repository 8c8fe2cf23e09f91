"""The numbers compiled kernels (njit) and the Python side agree on, one table per kind, each
value given once (issue 54, item 2): the error codes a kernel writes to ``error[0]`` (and the
step loop to its ``INFO_CODE``), and the kind codes of the compiled hole sections.

The modules that own a code read it from here by name (``ERR_LEFT_BORE =
ERROR_CODES["left_bore"]``); a value used twice is refused at import, so two owners can
never mean the same number, and ``tests/test_codes.py`` checks that every ``ERR_*`` and
``SHAPE_*`` constant of the package comes from these tables and that every compiled section
is dispatched. A new kind adds one line here. (This module's text names njit on purpose: the
compiled kernels' cache stamp covers the modules that do, flexmbs._jit.package_stamp, and the
kernels hold these values as constants.)
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

__all__ = ["ERROR_CODES", "SHAPE_CODES"]


def _unique(kind: str, table: dict[str, int]) -> Mapping[str, int]:
    seen: dict[int, str] = {}
    for name, value in table.items():
        if value in seen:
            raise ValueError(f"{kind} code {value} given to both {seen[value]!r} and {name!r}")
        seen[value] = name
    return MappingProxyType(table)


#: error codes of the compiled terms and the step loop, by name (0: no error)
ERROR_CODES = _unique("error", {
    "left_bore": 1,            # contact.clearance_term: the beam axis left the bore
    "end_of_beam": 2,          # constraints.sliding: a ring slid off its beam's end
    "too_many_contacts": 3,    # contact.clearance_term: more contacts than the tangent holds
    "off_plan": 4,             # constraints.sliding: the ring left its plan's window
    "contact_off_plan": 5,     # contact.clearance_term: a contact left its plan's window
    "node_turned": 11,         # elements.ancf_rod: a node turned past its chart's limit
    "singular": 100,           # steploop: a zero pivot
    "step_error": 101,         # steploop: a converged step refused for its local error
})

#: kind codes of the compiled hole sections (HoleSection.compiled_shape), by registry name
SHAPE_CODES = _unique("shape", {
    "circle": 0,
    "superellipse": 1,
    "rounded_rectangle": 2,
    "rounded_polygon": 3,
})
