"""``--set KEY=VALUE`` overrides of a parsed scenario (CLI ``flexmbs run --set``).

The override edits the parsed TOML in place before validation, so an overridden value is checked
like the file itself.
"""

from __future__ import annotations

from typing import Any

from ..errors import ScenarioError
from .tables import show_value, tomllib

__all__ = ["ARRAY_KEYS", "apply_override", "parse_value"]

#: top-level keys holding arrays of tables (``[[beams]]``), addressed by entry name or index
ARRAY_KEYS = ("beams", "rigid_bodies", "constraints", "joints", "tendons", "loads", "springs",
              "probes")


def apply_override(raw: dict[str, Any], assignment: str) -> None:
    """Apply ``KEY=VALUE`` (the CLI ``--set``) to a parsed scenario in place.

    ``KEY`` is a dotted path; entries of arrays of tables are addressed by their ``name`` (or
    by index): ``beams.rail.elements=8``, ``joints.sleeve.clearance=1e-3``,
    ``simulation.newton.max_iterations=40``. ``VALUE`` is parsed as a TOML value (numbers,
    booleans, strings, arrays, inline tables); a bare word is a string. Missing tables on the
    way are created; the loader then validates the result like the file itself.
    """
    if "=" not in assignment:
        raise ScenarioError(f"--set {assignment}: expected KEY=VALUE, e.g. simulation.dt=2e-4")
    key, _, text = assignment.partition("=")
    try:
        parts = _split_key(key)
    except ValueError:
        raise ScenarioError(f"--set {assignment}: invalid key {key.strip()!r}") from None
    value = parse_value(text)
    node: Any = raw
    done: list[str] = []
    for part in parts[:-1]:
        where = ".".join(done) or "the top level"
        if isinstance(node, list):
            node = _array_entry(node, part, assignment, where)
        elif isinstance(node, dict):
            if part not in node:
                # a missing array of tables has no entries to address; anything else is a table
                node[part] = [] if (node is raw and part in ARRAY_KEYS) else {}
            node = node[part]
        else:
            raise ScenarioError(f"--set {assignment}: {where} is {show_value(node)}, not a table")
        done.append(part)
    last = parts[-1]
    where = ".".join(done) or "the top level"
    if isinstance(node, list):
        raise ScenarioError(f"--set {assignment}: {where} is an array of tables; name an entry "
                            f"and a key, e.g. {where}.<name>.<key>=...")
    if not isinstance(node, dict):
        raise ScenarioError(f"--set {assignment}: {where} is {show_value(node)}, not a table")
    node[last] = value


def parse_value(text: str) -> Any:
    """The value of ``KEY=VALUE``: a TOML value, or a bare word as a string."""
    text = text.strip()
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text   # a bare word: a string


def _split_key(key: str) -> list[str]:
    """``beams.rail.elements`` and ``beams[rail].elements`` -> ['beams', 'rail', 'elements']."""
    parts: list[str] = []
    for chunk in key.replace("[", ".").replace("]", "").split("."):
        chunk = chunk.strip()
        if not chunk:
            raise ValueError("empty key segment")
        parts.append(chunk.strip("\"'"))
    return parts


def _array_entry(entries: list[Any], part: str, assignment: str, where: str) -> Any:
    for e in entries:
        if isinstance(e, dict) and e.get("name") == part:
            return e
    if part.lstrip("-").isdigit() and -len(entries) <= int(part) < len(entries):
        return entries[int(part)]
    names = [e["name"] for e in entries if isinstance(e, dict) and isinstance(e.get("name"), str)]
    known = ", ".join(names) if names else f"indices 0..{len(entries) - 1}" if entries else "none"
    raise ScenarioError(f"--set {assignment}: no entry '{part}' in {where} (entries: {known})")
