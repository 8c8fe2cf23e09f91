"""Checkpoints from other versions (issue 57, item 5): a checkpoint carries its format version;
a newer one is refused naming both versions, an older one resumes when the code knows how and
is otherwise refused saying what it lacks and how to continue; the frames stay readable."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import pytest

from flexmbs import __version__
from flexmbs.cli import main
from flexmbs.io import checkpoint
from flexmbs.io.checkpoint import FORMAT_VERSION, CheckpointVersionError, load_checkpoint
from tests.test_bad_inputs_answered_in_one_line import CANTILEVER, _refused


def _retag(path: Path, version: int, written_by: str) -> None:
    """Rewrite the checkpoint's format tag and writer version (every other entry kept)."""
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["format"] = np.array(f"flexmbs-checkpoint-{version}")
    arrays["flexmbs_version"] = np.array(written_by)
    buf = io.BytesIO()
    np.savez(buf, **arrays)  # type: ignore[arg-type]
    path.write_bytes(buf.getvalue())
    assert zipfile.is_zipfile(path)


@pytest.fixture(scope="module")
def stopped_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("ckpt") / "out"
    assert main(["run", CANTILEVER, "--t-end", "0.02", "--out", str(out), "-q"]) == 0
    return out


def test_the_checkpoint_carries_its_format_version(stopped_run: Path) -> None:
    with np.load(stopped_run / "checkpoint.npz", allow_pickle=False) as z:
        assert str(z["format"]) == f"flexmbs-checkpoint-{FORMAT_VERSION}"
        assert str(z["flexmbs_version"]) == __version__


def test_a_newer_checkpoint_is_refused_naming_both_versions(stopped_run: Path, tmp_path: Path,
                                                           capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    out.mkdir()
    for f in stopped_run.iterdir():
        if f.is_file():
            (out / f.name).write_bytes(f.read_bytes())
    _retag(out / "checkpoint.npz", FORMAT_VERSION + 1, "9.9.9")
    frames = sorted(p.name for p in out.iterdir())
    line = _refused(["run", CANTILEVER, "--resume", str(out), "--t-end", "0.04", "-q"], capsys,
                    "newer flexmbs (9.9.9", f"format {FORMAT_VERSION + 1}",
                    f"this flexmbs {__version__}", "run again without --resume")
    assert "damaged" not in line
    assert sorted(p.name for p in out.iterdir()) == frames     # nothing written


def test_an_older_checkpoint_resumes_when_known_else_says_what_it_lacks(
        stopped_run: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "checkpoint.npz"
    path.write_bytes((stopped_run / "checkpoint.npz").read_bytes())
    state, _ = load_checkpoint(path)
    _retag(path, 0, "0.0.1")
    with pytest.raises(CheckpointVersionError, match=r"format 0 \(flexmbs 0\.0\.1\), which lacks "
                       r"entries this flexmbs needs.*run again without --resume"):
        load_checkpoint(path)
    monkeypatch.setitem(checkpoint.OLDER_FORMATS, 0, "the friction anchors")
    with pytest.raises(CheckpointVersionError, match="lacks the friction anchors"):
        load_checkpoint(path)
    monkeypatch.setitem(checkpoint.OLDER_FORMATS, 0, None)     # readable as it is
    old, _ = load_checkpoint(path)
    assert old.t == state.t and np.array_equal(old.q, state.q)
