"""What a model and a run will need, estimated before anything is allocated or written
(issue "nothing lost": a billion elements, ten million hole sections, ``t_end = 1e12`` or
``dt = 1e-300`` must be one line, not a frozen machine or a traceback).

The figures per element, per section and per output frame were measured on the cable
(``tests/test_budget.py`` re-measures the frame size): the assembled run (sparse Jacobian and
its factors, integrator state, output buffers) takes about 10 kB per element and 0.7 kB per
hole section above a base of about 100 MB; a VTU frame takes about 1.8 kB per beam element.
Estimates are rounded up; a run is refused when it cannot fit this machine's available memory
or the output folder's free disk, and warned about when it will take hours or fill a large
part of the disk.
"""

from __future__ import annotations

import math
import os
import shutil
import warnings
from pathlib import Path
from typing import Any

from .errors import FlexmbsWarning, ModelError

__all__ = ["MAX_SECTIONS", "available_memory", "check_run", "require_memory"]

BASE_BYTES = 150e6
BYTES_PER_ELEMENT = 12e3
#: a clearance-joint section: its candidate rows (8 x 21 doubles), the exact tangent's work for
#: two contacts (2 x 19 x 50 doubles, contact/clearance_term.contact_capacity), tracked contacts
BYTES_PER_SECTION = 17e3
FRAME_BYTES_PER_ELEMENT = 1.8e3
FRAME_BYTES_BASE = 4e3
#: a crude lower bound of the cost of one time step (a small model on this machine: 40-125 us)
SECONDS_PER_STEP = 20e-6
SECONDS_PER_ELEMENT_STEP = 2e-6
SECONDS_PER_SECTION_STEP = 4e-6
MAX_STEPS = 1e11
#: sections per hole: beyond this the stations are closer than any beam element can resolve
#: and every Newton iteration pays ~1.5 us per section (a 40 mm hole: 0.4 um apart)
MAX_SECTIONS = 100_000
MAX_FRAMES = 1e6
WARN_SECONDS = 3600.0


def available_memory() -> float:
    """Memory available to a new allocation on this machine (bytes; ``MemAvailable``)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return math.inf


def _size(n: float) -> str:
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n / 1e3:.3g} kB"


def _duration(s: float) -> str:
    for unit, scale in (("years", 3.15e7), ("days", 86400.0), ("hours", 3600.0), ("min", 60.0)):
        if s >= scale:
            return f"{s / scale:.3g} {unit}"
    return f"{s:.3g} s"


def require_memory(n_elements: float = 0, n_sections: float = 0, *, what: str, fix: str) -> None:
    """Refuse (ModelError, one line) a model whose estimated memory exceeds what this machine
    has available; ``what`` names the input, ``fix`` says what to change."""
    need = BASE_BYTES + BYTES_PER_ELEMENT * n_elements + BYTES_PER_SECTION * n_sections
    have = available_memory()
    if need > have:
        raise ModelError(f"{what}: a model of this size needs about {_size(need)} of memory; "
                         f"this machine has {_size(have)} available; {fix}")


def _model_size(model: Any) -> tuple[int, int]:
    elements = sum(int(b.n_elem) for b in getattr(model, "beams", ()))
    sections = 0
    for j in getattr(model, "interactions", ()):
        hole = getattr(j, "hole", None)
        sections += int(getattr(hole, "sections", 0) or 0)
    return elements, sections


def check_times(*, t_end: float, dt: float, output_interval: float | None,
                t_start: float = 0.0, prefix: str = "") -> None:
    """The run's times, the one check every entry uses (:func:`check_run`,
    :func:`~flexmbs.solvers.generalized_alpha.integrate`): finite, ``0 < dt <= t_end −
    t_start``, ``output_interval`` > 0. ModelError naming the setting (``prefix``: see
    :func:`check_run`)."""
    t_key, dt_key, out_key = (f"{prefix}{k}" for k in ("t_end", "dt", "output_interval"))
    for name, value in ((t_key, t_end), (dt_key, dt)):
        if not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise ModelError(f"{name} must be a finite number (got {value!r})")
    if not dt > 0:
        raise ModelError(f"{dt_key} must be > 0 (got {dt!r})")
    span = t_end - t_start
    if not span > 0:
        raise ModelError(f"{t_key} = {t_end!r} must be later than the start time {t_start!r}")
    if dt > span * (1 + 1e-12):
        raise ModelError(f"{dt_key} = {dt!r} is longer than the run ({span!r} s); give "
                         f"{dt_key} <= {t_key}")
    if output_interval is not None and not (math.isfinite(output_interval) and output_interval > 0):
        raise ModelError(f"{out_key} must be a finite number > 0 (got {output_interval!r})")


def check_run(model: Any, *, t_end: float, dt: float, output_interval: float | None,
              out: str | os.PathLike[str] | None, t_start: float = 0.0, prefix: str = "") -> None:
    """Before a run: refuse (ModelError) what cannot run here (memory, disk, more than
    ``MAX_STEPS`` steps or ``MAX_FRAMES`` output frames), warn (FlexmbsWarning, once per
    message) about what will take hours or fill much of the disk. ``prefix`` goes before the
    names ``t_end``, ``dt``, ``output_interval`` in messages (``"simulation."`` for scenarios)."""
    t_key, dt_key, out_key = (f"{prefix}{k}" for k in ("t_end", "dt", "output_interval"))
    check_times(t_end=t_end, dt=dt, output_interval=output_interval, t_start=t_start,
                prefix=prefix)
    span = t_end - t_start
    elements, sections = _model_size(model)
    require_memory(elements, sections, what=f"{elements} beam elements and {sections} hole sections",
                   fix="use fewer elements or sections")
    steps = span / dt
    if steps > MAX_STEPS:
        raise ModelError(f"{t_key} / {dt_key} = {steps:.3g} steps ({t_key} = {t_end!r}, "
                         f"{dt_key} = {dt!r}): more "
                         f"than {MAX_STEPS:.0e}, which would take longer than "
                         f"{_duration(MAX_STEPS * SECONDS_PER_STEP)}; give a larger dt or a "
                         "shorter t_end")
    seconds = steps * (SECONDS_PER_STEP + SECONDS_PER_ELEMENT_STEP * elements
                       + SECONDS_PER_SECTION_STEP * sections)
    if seconds > WARN_SECONDS:
        warnings.warn(f"{steps:.3g} time steps of a model with {elements} elements and "
                      f"{sections} hole sections: at least about {_duration(seconds)} on one "
                      "core; Ctrl-C stops it with its output kept (--resume continues)",
                      FlexmbsWarning, stacklevel=1)
    if out is None:
        return
    frames = span / (output_interval or dt) + 1
    if frames > MAX_FRAMES:
        raise ModelError(f"{frames:.3g} output frames ({t_key} = {t_end!r}, {out_key} = "
                         f"{output_interval or dt!r}): more than {MAX_FRAMES:.0e} files; give a "
                         f"larger {out_key}")
    need = frames * (FRAME_BYTES_BASE + FRAME_BYTES_PER_ELEMENT * elements)
    folder = Path(out).resolve()
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    try:
        free = float(shutil.disk_usage(folder).free)
    except OSError:
        return
    if need > free:
        raise ModelError(f"{frames:.3g} output frames of {elements} elements need about "
                         f"{_size(need)} in {out}; the disk has {_size(free)} free; give a larger "
                         f"{out_key} or fewer elements")
    if need > 0.5 * free or need > 20e9:
        warnings.warn(f"the output will take about {_size(need)} in {out} ({_size(free)} free); "
                      f"a larger {out_key} writes less", FlexmbsWarning, stacklevel=1)
