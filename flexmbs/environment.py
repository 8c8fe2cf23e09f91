"""The environment variables flexmbs reads, declared once (docs/cli.md, "Environment").

The ``flexmbs`` command checks them all before it does anything (:func:`check_environment`):
a value that is none of the declared ones is one line naming the variable and what it may be,
exit 2, instead of being ignored or failing halfway through a run. The test of every key and
flag (tests/io/test_every_key.py) generates a bad value for each from this table, and checks
that the package reads no ``FLEXMBS_*`` variable it does not declare.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass

from .errors import FlexmbsError

__all__ = ["ENVIRONMENT", "Variable", "check_environment"]


@dataclass(frozen=True, kw_only=True)
class Variable:
    """One environment variable: its values (``choices``; ``""`` = unset) or, with
    ``file=True``, the path of an existing file."""

    name: str
    meaning: str
    choices: tuple[str, ...] = ()
    file: bool = False
    case_sensitive: bool = True

    def problem(self, value: str) -> str | None:
        """Why ``value`` is not a value of this variable (None if it is)."""
        if self.file:
            if value and not os.path.isfile(value):
                return f"expected the path of an existing file ({self.meaning})"
            return None
        v = value.strip() if self.case_sensitive else value.strip().lower()
        if v not in self.choices:
            shown = ", ".join(c for c in self.choices if c) or "none"
            return f"expected one of {shown} ({self.meaning})"
        return None


#: every ``FLEXMBS_*`` variable the package reads
ENVIRONMENT: tuple[Variable, ...] = (
    Variable(name="FLEXMBS_KERNEL", choices=("", "auto", "own", "complete"),
             case_sensitive=False,
             meaning="which compiled kernel serves a model: auto, own or complete"),
    Variable(name="FLEXMBS_DISABLE_JIT", choices=("", "0", "1"),
             meaning="1 runs the numba kernels as plain Python, for debugging"),
    Variable(name="FLEXMBS_KLU_LIBRARY", file=True,
             meaning="the KLU shared library to use, e.g. /usr/lib/libklu.so.2"),
)


def check_environment(environ: Mapping[str, str] | None = None) -> None:
    """Raise :class:`~flexmbs.errors.FlexmbsError` naming the first variable of
    :data:`ENVIRONMENT` set to a value it cannot take."""
    env = os.environ if environ is None else environ
    for var in ENVIRONMENT:
        value = env.get(var.name)
        if value is None:
            continue
        problem = var.problem(value)
        if problem is not None:
            raise FlexmbsError(f"environment variable {var.name}={value!r}: {problem}; correct "
                               f"it or unset it (unset {var.name})")
