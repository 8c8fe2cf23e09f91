"""Which public names (``flexmbs.__all__``) have a complete numpydoc docstring.

Complete: a docstring; for a function or a class whose constructor takes arguments, a
``Parameters`` section naming every argument; for a function that returns something, a
``Returns`` section. Exceptions and constants need only a docstring.

    python tools/docstring_coverage.py [-v]
"""

from __future__ import annotations

import inspect
import re
import sys

import flexmbs


def _section(doc: str, title: str) -> str | None:
    m = re.search(rf"^\s*{title}\n\s*-{{3,}}\n(.*?)(?=^\s*\w[\w ]*\n\s*-{{3,}}\n|\Z)", doc, re.S | re.M)
    return m.group(1) if m else None


def missing(name: str) -> list[str]:
    """What the docstring of ``flexmbs.<name>`` lacks (empty: complete)."""
    obj = getattr(flexmbs, name)
    doc = inspect.getdoc(obj) or ""
    if not doc or (inspect.isclass(obj) and doc == inspect.getdoc(object)):
        return ["docstring"]
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return []
    if not (inspect.isclass(obj) or inspect.isfunction(obj)):
        return []
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    params = [p for p in sig.parameters.values()
              if p.name not in ("self", "cls") and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    lack = []
    if params:
        section = _section(doc, "Parameters") or ""
        if not section:
            lack.append("Parameters")
        else:
            named = set(re.findall(r"^(\w+)(?:\s*,\s*(\w+))*\s*:", section, re.M))
            listed = {n for group in named for n in group if n}
            listed |= set(re.findall(r"^(\w+)\b", section, re.M))
            lack.extend(f"parameter {p.name}" for p in params if p.name not in listed)
    if inspect.isfunction(obj) and sig.return_annotation not in (None, "None", inspect.Signature.empty) \
            and _section(doc, "Returns") is None:
        lack.append("Returns")
    return lack


def main(argv: list[str] | None = None) -> int:
    verbose = "-v" in (argv if argv is not None else sys.argv[1:])
    names = [n for n in flexmbs.__all__ if n != "__version__"]
    complete = 0
    for n in names:
        lack = missing(n)
        complete += not lack
        if verbose and lack:
            print(f"{n}: missing {', '.join(lack)}")
    print(f"{complete} of {len(names)} public names have a complete docstring")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
