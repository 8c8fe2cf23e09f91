"""The code a newcomer copies runs: the README's Python snippet and every code block of the
tutorial (docs/getting-started.md), in order, in an empty folder."""

from __future__ import annotations

import importlib.util
import re
import shlex
from pathlib import Path

import pytest

from flexmbs.cli import main

ROOT = Path(__file__).resolve().parents[1]
_BLOCK = re.compile(r"^```(\w+)\n(.*?)^```", re.S | re.M)


def _blocks(path: Path) -> list[tuple[str, str]]:
    return [(m.group(1), m.group(2)) for m in _BLOCK.finditer(path.read_text(encoding="utf-8"))]


def test_readme_python_snippet_runs(tmp_path, monkeypatch):
    snippets = [code for lang, code in _blocks(ROOT / "README.md") if lang == "python"]
    assert len(snippets) == 1
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(snippets[0], "README.md", "exec"), namespace)
    result = namespace["result"]
    assert result.status == "completed"
    assert (tmp_path / "out" / "sleeve" / "summary.json").is_file()


def test_tutorial_code_blocks_run(tmp_path, monkeypatch):
    """Python blocks share one namespace; a TOML block whose first line is ``# NAME`` is saved
    as NAME; the ``flexmbs`` lines of bash blocks run through :func:`flexmbs.cli.main` (an
    install line is skipped: the suite runs in an installed environment)."""
    blocks = _blocks(ROOT / "docs" / "getting-started.md")
    assert [lang for lang, _ in blocks].count("python") >= 4
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    missing = []
    for lang, code in blocks:
        if lang == "python":
            needs = [m for m in ("pandas", "pyvista") if f"import {m}" in code]
            lacking = [m for m in needs if importlib.util.find_spec(m) is None]
            if lacking:         # the test extra has them; elsewhere the other blocks still run
                missing.extend(lacking)
                continue
            exec(compile(code, "getting-started.md", "exec"), namespace)
        elif lang == "toml":
            name = code.splitlines()[0].lstrip("# ").strip()
            (tmp_path / name).write_text(code, encoding="utf-8")
        elif lang == "bash":
            for line in code.splitlines():
                words = shlex.split(line, comments=True)
                if not words or words[0] == "pip":
                    continue
                assert words[0] == "flexmbs", line
                if words[1] in ("plot", "render"):
                    pytest.importorskip("matplotlib")
                    pytest.importorskip("pyvista")
                    words.append("--quiet")
                assert main(words[1:]) == 0, line
    assert namespace["run"].summary["status"] == "completed"
    if missing:
        pytest.skip(f"the blocks that import {', '.join(missing)} did not run (not installed)")
