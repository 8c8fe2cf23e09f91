"""Issue "nothing lost, part three", item 1: every scenario key gets bad values, generated from
the keys' declarations rather than written by hand.

Each key is declared once, where its builder reads it (``t.number("radius", gt=0, unit="m")``,
a contact law's or hole shape's dataclass field metadata); :func:`flexmbs.io.tables.record_keys`
collects the declarations while the coverage scenarios of ``tests/data/keys/`` load. From each
declaration come a wrong type, a value out of its range and, for a key with a unit, an absurd
magnitude; each is given to ``flexmbs run --set`` and must be answered in one line naming the
key path, exit 2, with no output folder. A new key cannot escape: every key a table allows
must be declared and reached by a coverage scenario, and every registered builder, hole shape
and contact law must be used by one (:func:`test_every_key_is_declared_and_reached`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import pytest

from flexmbs.cli import main
from flexmbs.contact.laws import CONTACT_LAWS
from flexmbs.contact.sections import HOLE_SECTIONS
from flexmbs.io.builders import CONSTRAINTS, ELEMENTS, JOINTS, LOADS, PROBES, SPRINGS
from flexmbs.io.scenario import load_scenario
from flexmbs.io.tables import UNITS, KeyUse, record_keys

ROOT = Path(__file__).resolve().parents[2]
KEYS = ROOT / "tests" / "data" / "keys"
FILES = sorted(KEYS.glob("*.toml"))
REGISTRIES = (ELEMENTS, CONSTRAINTS, JOINTS, LOADS, SPRINGS, PROBES, HOLE_SECTIONS, CONTACT_LAWS)
#: TOML spelling of the absurd magnitude given to every key with a unit
ABSURD = 1e30


def pattern(path: str) -> str:
    """``beams[rail].geometry`` -> ``beams[].geometry`` (one key, whatever the entry)."""
    return re.sub(r"\[[^\]]*\]", "[]", path)


@dataclass(frozen=True)
class Declared:
    """One key (its pattern) and the occurrence its bad values are tried on."""

    file: Path
    use: KeyUse

    @property
    def pattern(self) -> str:
        return pattern(self.use.full)


@cache
def collect() -> tuple[dict[str, Declared], set[tuple[str, str]], set[tuple[str, str]]]:
    """The declared keys by pattern (an occurrence where the key is present preferred), the
    ``(table pattern, key)`` pairs the tables allow, and the registry entries looked up."""
    keys: dict[str, Declared] = {}
    allowed: set[tuple[str, str]] = set()
    lookups: set[tuple[str, str]] = set()
    for f in FILES:
        with record_keys() as rec:
            load_scenario(f)
        for use in rec.uses:
            d = Declared(f, use)
            old = keys.get(d.pattern)
            if old is None or (use.present and not old.use.present):
                keys[d.pattern] = d
        allowed |= {(pattern(path), k) for path, ks in rec.allowed for k in ks}
        lookups |= set(rec.lookups)
    return keys, allowed, lookups


def _out_of_range(u: KeyUse) -> str | None:
    if u.gt is not None:
        return repr(float(u.gt))
    if u.ge is not None:
        return repr(float(u.ge) - 1.0)
    if u.lt is not None:
        return repr(float(u.lt))
    if u.le is not None:
        return repr(float(u.le) + 1.0)
    return "nan"


def bad_values(u: KeyUse) -> list[tuple[str, str]]:
    """``(what, TOML value)`` pairs: a wrong type, out of range, an absurd magnitude."""
    unit = u.unit not in (None, "1")
    if u.kind == "number":
        out = [("type", '"x"'), ("range", _out_of_range(u) or "nan")]
        return out + ([("size", repr(ABSURD))] if unit else [])
    if u.kind == "integer":
        lo = u.ge - 1 if u.ge is not None else None
        return [("type", "1.5"), *([("range", str(lo))] if lo is not None else []),
                *([("range_hi", str(int(u.le) + 1))] if u.le is not None else [])]
    if u.kind == "vector":
        n = u.n or 3
        out = [("type", '"x"'), ("range", "[" + ", ".join(["1.0"] * (n - 1)) + "]")]
        return out + ([("size", "[" + ", ".join([repr(ABSURD)] * n) + "]")] if unit else [])
    if u.kind == "function":
        return [("type", "true"), *([("size", repr(ABSURD))] if unit else [])]
    if u.kind == "boolean":
        return [("type", "1")]
    if u.kind == "choice":
        return [("type", "3"), ("range", '"no_such_choice"')]
    if u.kind in ("string", "name"):
        return [("type", "3"), ("range", '""')]
    if u.kind == "table":
        return [("type", "3")]
    if u.kind == "tables":
        return [("type", "3")]
    assert u.kind == "value", u
    return [("type", "true")]


def cases() -> list[tuple[str, Path, str, str, str]]:
    keys, allowed, _ = collect()
    out = []
    for pat, d in sorted(keys.items()):
        table = pattern(d.use.path)
        if any(t == table for t, _ in allowed) and (table, d.use.key) not in allowed:
            continue        # read by a shared reader, but not a key of this table
        for what, value in bad_values(d.use):
            out.append((f"{pat}:{what}", d.file, d.use.full, what, value))
    return out


def test_every_key_is_declared_and_reached():
    keys, allowed, lookups = collect()
    missing = sorted(f"{t}.{k}" if t else k for t, k in allowed
                     if pattern(f"{t}.{k}" if t else k) not in keys)
    assert not missing, ("keys a table allows that no coverage scenario of tests/data/keys/ "
                         f"reads through a declaring getter: {missing}")
    unused = sorted(f"{r.kind} {name}" for r in REGISTRIES for name in r
                    if (r.kind, name) not in lookups)
    assert not unused, f"registered parts no coverage scenario uses: {unused}"
    no_unit = sorted(p for p, d in keys.items()
                     if d.use.kind in ("number", "vector", "function")
                     and d.use.unit not in UNITS)
    assert not no_unit, f"number keys without a declared unit (flexmbs.io.tables.UNITS): {no_unit}"
    assert len(keys) > 250


@pytest.mark.parametrize("case", cases(), ids=lambda c: c[0])
def test_a_bad_value_is_one_line_naming_the_key(case, tmp_path, capsys):
    _, file, path, what, value = case
    out = tmp_path / "out"
    code = main(["run", str(file), "--set", f"{path}={value}", "--out", str(out), "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, (code, err)
    # an entry is named by its name, or by its index when the bad value is its name
    named = {path, re.sub(r"\[[^\]]*\]\.name$", "", path)}
    assert any(p in err[0] for p in named) or re.search(
        re.escape(path.rsplit("[", 1)[0]) + r"\[\d+\]\.name", err[0]), err[0]
    assert not out.exists()
    assert re.search(r"expected|known|belongs to|only with|only for|give |must ", err[0]), err[0]


# ------------------------------------------------------------------ flags and environment
def flag_cases() -> list[tuple[str, list[str], str]]:
    """``(id, argv, flag)``: for every flag whose value is declared (a
    :class:`~flexmbs.commands._common.Number` type or choices), a wrong type and a value out of
    its range."""
    import argparse

    from flexmbs.cli import build_parser
    from flexmbs.commands._common import Number

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    scenario = str(ROOT / "examples" / "cantilever.toml")
    out = []
    for command, p in sub.choices.items():
        first = [] if command == "compile" else [scenario if command in ("run", "info", "sweep")
                                                 else str(KEYS / "no_such_run")]
        for a in p._actions:
            if not a.option_strings:
                continue
            flag = a.option_strings[0]
            bad: list[tuple[str, str]] = []
            if isinstance(a.type, Number):
                bad.append(("type", "x"))
                if a.type.gt is not None or a.type.ge is not None:
                    lo = a.type.gt if a.type.gt is not None else a.type.ge - 1
                    bad.append(("range", str(int(lo)) if a.type.integer else repr(float(lo))))
                elif a.type.integer:
                    bad.append(("range", "1.5"))
                else:
                    bad.append(("range", "nan"))
            elif a.choices:
                bad += [("type", "3"), ("range", "no_such_choice")]
            for what, value in bad:
                out.append((f"{command} {flag}:{what}", [command, *first, f"{flag}={value}"], flag))
    return out


@pytest.mark.parametrize("case", flag_cases(), ids=lambda c: c[0])
def test_a_bad_flag_value_is_one_line_naming_the_flag(case, capsys):
    _, argv, flag = case
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and flag in err[0], err
    assert re.search(r"expected|invalid choice", err[0]), err[0]


def test_every_variable_the_package_reads_is_declared():
    from flexmbs.environment import ENVIRONMENT

    read = set()
    for folder in ("flexmbs", "postprocess"):
        for f in (ROOT / folder).rglob("*.py"):
            read |= set(re.findall(r"FLEXMBS_[A-Z_]+", f.read_text(encoding="utf-8")))
    declared = {v.name for v in ENVIRONMENT}
    assert read - {"FLEXMBS_"} <= declared, read - declared
    assert declared <= read


def _variable_cases() -> list[tuple[str, str]]:
    from flexmbs.environment import ENVIRONMENT

    out = []
    for v in ENVIRONMENT:
        out.append((v.name, "/no/such/file" if v.file else "no_such_value"))
        if not v.file:
            out.append((v.name, "3"))
    return out


@pytest.mark.parametrize("name, value", _variable_cases())
def test_a_bad_environment_variable_is_one_line_naming_it(name, value, tmp_path, capsys,
                                                           monkeypatch):
    monkeypatch.setenv(name, value)
    out = tmp_path / "out"
    assert main(["run", str(ROOT / "examples" / "cantilever.toml"), "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"environment variable {name}={value!r}: expected" in err[0], err
    assert not out.exists()


def test_bores_of_different_section_counts_in_one_model_run(tmp_path):
    """Found by the bad values above (a friction table replaced by a number let the coverage
    scenario run): joints whose bores have different numbers of sections in one model failed
    at the first step with an IndexError (the tip sections' slice took the padding)."""
    out = tmp_path / "out"
    assert main(["run", str(KEYS / "joints.toml"), "--out", str(out), "-q"]) == 0
    assert (out / "summary.json").is_file()
