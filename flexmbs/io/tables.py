"""Typed reading of TOML tables with key paths and one-line errors (scenario files).

:class:`Table` wraps one parsed table and its key path (``beams[rail]``); every getter checks
type and range and raises :class:`~flexmbs.errors.ScenarioError` with a message that starts with
the key path: ``beams[rail].radius: expected a number > 0, got -0.002``. Arrays of tables are
addressed by the entry's ``name`` when it has one (``beams[rail]``), otherwise by index
(``constraints[0]``). :func:`read_toml` parses a file; :func:`at` turns errors of the Python API
raised while a table is built into ScenarioErrors naming the table.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import sys
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from ..errors import GeometryError, ModelError, ScenarioError
from ..registry import Registry

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - python 3.10
    import tomli as tomllib

__all__ = ["MISSING", "UNITS", "KeyRecord", "KeyUse", "Table", "at", "display_path", "is_number",
           "one_line", "read_toml", "record_keys", "show_value", "tomllib"]

T = TypeVar("T")

#: default of a required key
MISSING: Any = object()

#: the unit of every number a scenario key holds -> the largest magnitude it may have (SI).
#: A key declares its unit where it is read (``t.number("radius", gt=0, unit="m")``); a value
#: beyond this size is not a model of anything (a radius of 1e30 m) and is refused naming the
#: key. Stiffnesses are left room for parts made stiff on purpose (a rail of 1000 times steel's
#: modulus stands for a rigid track). ``"1"``: dimensionless, bounded only by the key's range.
UNITS: dict[str, float] = {
    "1": math.inf, "m": 1e6, "s": 1e12, "rad": 1e6, "Hz": 1e9, "m/s": 1e6, "rad/s": 1e6,
    "m/s^2": 1e7, "1/s": 1e9, "1/s^2": 1e12, "kg": 1e12, "kg/m": 1e6, "kg/m^3": 1e6,
    "kg m": 1e9, "kg m^2": 1e15, "N": 1e15, "N m": 1e15, "N m^2": 1e18, "Pa": 1e18,
    "N/m": 1e18, "N/m^n": 1e18, "N s/m": 1e15, "N m/rad": 1e18, "N m s/rad": 1e15,
}


@dataclasses.dataclass(frozen=True, kw_only=True)
class KeyUse:
    """One key read by a scenario builder: its declaration (kind, range, unit) as the typed
    getter that read it saw it (:func:`record_keys`)."""

    path: str                       #: the table's key path, e.g. ``beams[rail]``
    key: str
    kind: str                       #: number | integer | boolean | string | choice | vector |
    #: table | tables | value (any form, checked by its builder) | name
    present: bool                   #: the key was in the table
    unit: str | None = None
    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    choices: tuple[str, ...] = ()
    n: int | None = None            #: a vector's length

    @property
    def full(self) -> str:
        return f"{self.path}.{self.key}" if self.path else self.key


@dataclasses.dataclass
class KeyRecord:
    """What :func:`record_keys` saw: the keys read, the keys each table allows and the
    registry entries looked up."""

    uses: list[KeyUse] = dataclasses.field(default_factory=list)
    allowed: list[tuple[str, tuple[str, ...]]] = dataclasses.field(default_factory=list)
    lookups: list[tuple[str, str]] = dataclasses.field(default_factory=list)


_RECORDS: list[KeyRecord] = []


@contextmanager
def record_keys() -> Iterator[KeyRecord]:
    """Record every key the builders read while the block runs (the key tables of the
    scenario format, as tests/io/test_every_key.py generates its bad values from them)."""
    rec = KeyRecord()
    _RECORDS.append(rec)
    try:
        yield rec
    finally:
        _RECORDS.remove(rec)


def show_value(v: Any) -> str:
    """A value as the user wrote it (TOML spelling), shortened."""
    if isinstance(v, bool):
        s = "true" if v else "false"
    elif isinstance(v, str):
        s = repr(v)
    elif isinstance(v, Mapping):
        s = "a table {" + ", ".join(str(k) for k in v) + "}"
    elif isinstance(v, (list, tuple)):
        s = "[" + ", ".join(show_value(x) for x in v) + "]"
    else:
        s = repr(v)
    return s if len(s) <= 80 else s[:77] + "..."


def is_number(v: Any) -> bool:
    """An int or float that is not a bool."""
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def one_line(exc: BaseException) -> str:
    """The message of ``exc`` on one line."""
    return " ".join(str(exc).split())


def display_path(p: Path) -> str:
    """``relative/to/cwd`` (resolved ``/abs/path``)."""
    try:
        rel = os.path.relpath(p)
    except ValueError:  # another drive on Windows
        rel = str(p)
    return f"{rel} (resolved: {p.resolve()})"


def _bounds_text(gt: float | None, ge: float | None, lt: float | None, le: float | None) -> str:
    lo = (f"> {gt:g}" if gt is not None else f">= {ge:g}" if ge is not None else None)
    hi = (f"< {lt:g}" if lt is not None else f"<= {le:g}" if le is not None else None)
    if lo and hi:
        a = "(" if gt is not None else "["
        b = ")" if lt is not None else "]"
        return f" in {a}{gt if gt is not None else ge:g}, {lt if lt is not None else le:g}{b}"
    return f" {lo or hi}" if (lo or hi) else ""


@contextmanager
def at(path: str) -> Iterator[None]:
    """Re-raise model/geometry errors of the API as ScenarioError prefixed with ``path``."""
    try:
        yield
    except ScenarioError:
        raise
    except (ModelError, GeometryError, ValueError) as exc:
        raise ScenarioError(f"{path}: {one_line(exc)}") from exc


def read_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Parse a TOML file (no validation); a missing file or bad TOML is a ScenarioError."""
    p = Path(path)
    if not p.is_file():
        if p.is_dir():
            raise ScenarioError(f"scenario file is a directory, not a file: {display_path(p)}")
        if p.exists():      # /dev/null, a pipe, a socket
            raise ScenarioError(f"scenario file {display_path(p)} exists but is not a regular "
                                "file (a device, a pipe or a socket); give a .toml file")
        raise ScenarioError(f"scenario file not found: {display_path(p)}")
    try:
        with p.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{p}: invalid TOML: {one_line(exc)}") from exc
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{p}: invalid TOML: the file is not UTF-8 text ({exc.reason})") from exc


class Table:
    """Typed, path-aware access to one TOML table (raises ScenarioError naming the key path)."""

    def __init__(self, raw: Mapping[str, Any], path: str) -> None:
        self.raw = raw
        self.path = path

    def note(self, k: str, kind: str, **meta: Any) -> None:
        """Declare key ``k`` as read (for :func:`record_keys`; free when nothing records)."""
        if _RECORDS:
            use = KeyUse(path=self.path, key=k, kind=kind, present=k in self.raw, **meta)
            for rec in _RECORDS:
                rec.uses.append(use)

    def check_size(self, k: str, v: Any, unit: str | None, expected: str) -> None:
        """Refuse a value larger than its unit allows (:data:`UNITS`; ``None``: a plug-in's
        parameter that declares no unit, unchecked)."""
        if unit is None:
            return
        limit = UNITS[unit]
        values = v if isinstance(v, (list, tuple)) else [v]
        if any(is_number(x) and abs(x) > limit for x in values):
            raise self.fail(k, f"{expected} [{unit}] of a plausible size (at most {limit:g} "
                            f"{unit})", v)

    @property
    def name(self) -> Any:
        """The entry's ``name`` (None if it has none)."""
        return self.raw.get("name")

    def key(self, k: str) -> str:
        """Key path of ``k`` in this table."""
        return f"{self.path}.{k}" if self.path else k

    def where(self) -> str:
        return self.path or "the top level"

    def has(self, k: str) -> bool:
        return k in self.raw

    def present(self, keys: Iterable[str]) -> list[str]:
        return [k for k in keys if k in self.raw]

    def allow(self, keys: Iterable[str]) -> None:
        """Reject keys not in ``keys`` (with a close-match suggestion)."""
        allowed = list(keys)
        for rec in _RECORDS:
            rec.allowed.append((self.path, tuple(allowed)))
        for k in self.raw:
            if k not in allowed:
                close = difflib.get_close_matches(k, allowed, n=1, cutoff=0.6)
                hint = (f"; did you mean '{close[0]}'?" if close
                        else f" (allowed: {', '.join(sorted(allowed))})")
                raise ScenarioError(f"unknown key '{k}' in {self.where()}{hint}")

    def exclusive(self, *groups: str) -> str | None:
        """The one key of ``groups`` present (None if none); two or more is an error."""
        got = self.present(groups)
        if len(got) > 1:
            raise ScenarioError(f"{self.where()}: give only one of "
                                f"{', '.join(repr(g) for g in groups)} (got {', '.join(got)})")
        return got[0] if got else None

    def get(self, k: str, default: Any = MISSING, expected: str = "a value") -> Any:
        """The raw value of ``k`` (its builder checks it); ``default`` if absent."""
        self.note(k, "value")
        if k in self.raw:
            return self.raw[k]
        if default is MISSING:
            raise ScenarioError(f"{self.key(k)}: missing required key (expected {expected})")
        return default

    def fail(self, k: str, expected: str, got: Any) -> ScenarioError:
        """The error for key ``k``: ``<path>.k: expected <expected>, got <got>``."""
        return ScenarioError(f"{self.key(k)}: expected {expected}, got {show_value(got)}")

    def number(self, k: str, default: Any = MISSING, *, unit: str | None, gt: float | None = None,
               ge: float | None = None, lt: float | None = None, le: float | None = None) -> Any:
        """A finite number (float) in the given bounds and of a size its ``unit`` allows
        (:data:`UNITS`); ``default`` if absent."""
        self.note(k, "number", unit=unit, gt=gt, ge=ge, lt=lt, le=le)
        expected = "a number" + _bounds_text(gt, ge, lt, le)
        v = self._raw(k, default, expected)
        if v is default and k not in self.raw:
            return v
        if not is_number(v) or not math.isfinite(v):
            raise self.fail(k, expected.replace("a number", "a finite number")
                            if is_number(v) else expected, v)
        if ((gt is not None and not v > gt) or (ge is not None and not v >= ge)
                or (lt is not None and not v < lt) or (le is not None and not v <= le)):
            raise self.fail(k, expected, v)
        self.check_size(k, v, unit, expected)
        return float(v)

    def _raw(self, k: str, default: Any, expected: str) -> Any:
        if k in self.raw:
            return self.raw[k]
        if default is MISSING:
            raise ScenarioError(f"{self.key(k)}: missing required key (expected {expected})")
        return default

    def integer(self, k: str, default: Any = MISSING, *, ge: int | None = None,
                le: int | None = None) -> Any:
        """An integer in the given bounds; ``default`` if absent."""
        self.note(k, "integer", ge=ge, le=le)
        expected = "an integer" + _bounds_text(None, ge, None, le)
        v = self._raw(k, default, expected)
        if v is default and k not in self.raw:
            return v
        if not isinstance(v, int) or isinstance(v, bool):
            raise self.fail(k, expected, v)
        if (ge is not None and v < ge) or (le is not None and v > le):
            raise self.fail(k, expected, v)
        return int(v)

    def boolean(self, k: str, default: Any = MISSING) -> Any:
        """``true`` or ``false``; ``default`` if absent."""
        self.note(k, "boolean")
        v = self._raw(k, default, "true or false")
        if not isinstance(v, bool):
            raise self.fail(k, "true or false", v)
        return v

    def string(self, k: str, default: Any = MISSING) -> Any:
        """A non-empty string; ``default`` if absent."""
        self.note(k, "string")
        return self._string(k, default)

    def _string(self, k: str, default: Any) -> Any:
        v = self._raw(k, default, "a string")
        if v is default and k not in self.raw:
            return v
        if not isinstance(v, str) or not v:
            raise self.fail(k, "a non-empty string", v)
        return v

    def choice(self, k: str, choices: Sequence[str], default: Any = MISSING,
               what: str = "value") -> Any:
        """One of ``choices`` (a string); an unknown value lists the known ones."""
        self.note(k, "choice", choices=tuple(choices))
        v = self._string(k, default)
        if v not in choices:
            raise ScenarioError(f"{self.key(k)}: unknown {what} {show_value(v)} "
                                f"(known: {', '.join(choices)})")
        return v

    def lookup(self, k: str, registry: Registry[T], default: Any = MISSING) -> tuple[str, T]:
        """``(name, entry)`` of the registry entry named by key ``k``; an unknown name is the
        registry's message (``unknown <kind> 'x' (known: ...)``) after the key path."""
        self.note(k, "choice", choices=tuple(registry))
        name = self._string(k, default)
        for rec in _RECORDS:
            rec.lookups.append((registry.kind, name))
        if name not in registry:
            raise ScenarioError(f"{self.key(k)}: {registry.unknown(name)}")
        return name, registry.get(name)

    def kind(self, registry: Registry[T]) -> tuple[str, T]:
        """The entry of the ``type`` key; a misspelt ``type`` key is reported as such."""
        if not self.has("type"):
            close = difflib.get_close_matches("type", [str(k) for k in self.raw], n=1, cutoff=0.6)
            if close:
                raise ScenarioError(f"unknown key '{close[0]}' in {self.where()}; did you mean "
                                    "'type'?")
        return self.lookup("type", registry)

    def vector(self, k: str, default: Any = MISSING, *, unit: str | None, n: int = 3,
               what: str | None = None) -> Any:
        """``n`` finite numbers as an array, each of a size its ``unit`` allows; ``default``
        if absent."""
        self.note(k, "vector", unit=unit, n=n)
        expected = what or (f"{n} numbers [x, y, z]" if n == 3 else f"{n} numbers")
        v = self._raw(k, default, expected)
        if v is default and k not in self.raw:
            return v
        if (not isinstance(v, list) or len(v) != n
                or not all(is_number(x) and math.isfinite(x) for x in v)):
            raise self.fail(k, expected, v)
        self.check_size(k, v, unit, expected)
        return np.array(v, dtype=float)

    def table(self, k: str, default: Any = MISSING) -> Any:
        """The sub-table ``k`` as a :class:`Table`; ``default`` if absent."""
        self.note(k, "table")
        v = self._raw(k, default, "a table")
        if v is default and k not in self.raw:
            return v
        if not isinstance(v, Mapping):
            raise self.fail(k, "a table { ... }", v)
        return Table(v, self.key(k))

    def tables(self, k: str, *, need_name: bool) -> list[Table]:
        """An array of tables ``[[k]]``, each addressed as ``k[name]`` (or ``k[index]``)."""
        self.note(k, "tables")
        v = self._raw(k, [], "an array of tables [[...]]")
        if isinstance(v, Mapping):
            raise ScenarioError(f"{self.key(k)}: expected an array of tables [[{k}]], got a single "
                                f"table [{k}]; write [[{k}]]")
        if not isinstance(v, list):
            raise self.fail(k, f"an array of tables [[{k}]]", v)
        out: list[Table] = []
        seen: dict[str, int] = {}
        for i, entry in enumerate(v):
            if not isinstance(entry, Mapping):
                raise ScenarioError(f"{self.key(k)}[{i}]: expected a table, got {show_value(entry)}")
            name = entry.get("name")
            if "name" in entry and (not isinstance(name, str) or not name
                                    or not name.isprintable()):
                raise ScenarioError(f"{self.key(k)}[{i}].name: expected a non-empty string of "
                                    f"printable characters, got {show_value(name)}")
            if need_name and name is None:
                raise ScenarioError(f"{self.key(k)}[{i}].name: missing required key "
                                    f"(expected a unique name string)")
            if name is not None:
                if name in seen:
                    raise ScenarioError(f"{self.key(k)}[{i}].name: duplicate name '{name}' "
                                        f"(also {self.key(k)}[{seen[name]}]); names must be unique")
                seen[name] = i
            table = Table(entry, f"{self.key(k)}[{name if name is not None else i}]")
            table.note("name", "name")
            out.append(table)
        return out

    def parameters(self, cls: type, *, skip: Iterable[str] = ()) -> dict[str, Any]:
        """Keyword parameters of the dataclass ``cls`` read from this table: one key per init
        field (numbers; integers for ``int`` fields), required when the field has no default.
        A field declares its unit and range in its metadata
        (``field(metadata={"unit": "m", "gt": 0.0})``), checked here with the key path; ``cls``
        validates the rest. Only the keys present (and the required ones) are returned."""
        out: dict[str, Any] = {}
        skipped = set(skip)
        for f in dataclasses.fields(cls):
            if not f.init or f.name in skipped:
                continue
            required = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
            meta = dict(f.metadata)
            integer = f.type in (int, "int")
            bounds = {b: meta[b] for b in ("gt", "ge", "lt", "le") if b in meta}
            default = MISSING if required else None
            if integer:
                v = self.integer(f.name, default, ge=bounds.get("ge"), le=bounds.get("le"))
            else:
                v = self.number(f.name, default, unit=meta.get("unit"), **bounds)
            if v is not None:
                out[f.name] = v
        return out

    @staticmethod
    def parameter_names(cls: type, *, skip: Iterable[str] = ()) -> tuple[str, ...]:
        """The keys :meth:`parameters` reads for ``cls``."""
        skipped = set(skip)
        return tuple(f.name for f in dataclasses.fields(cls) if f.init and f.name not in skipped)
