"""Checkpoint round trip: the state and the interaction state come back bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from flexmbs.io.checkpoint import load_checkpoint, save_checkpoint
from flexmbs.solvers.generalized_alpha import State


def random_state(rng: np.random.Generator, n: int = 17, m: int = 5) -> State:
    return State(0.1 + 1e-17 * rng.random(), rng.standard_normal(n), rng.standard_normal(n),
                 rng.standard_normal(n), rng.standard_normal(n), rng.standard_normal(m))


def test_round_trip_is_bit_exact(tmp_path, rng):
    st = random_state(rng)
    extra = {"xi": rng.random(9), "elements": np.arange(9, dtype=np.int32),
             "active": np.array([True, False]), "step": 12, "h": 1 / 3,
             "history": {"sleeve": [0.1, 0.25]}, "name": "sleeve"}
    path = save_checkpoint(tmp_path / "c.npz", st, extra=extra)
    assert path == tmp_path / "c.npz"
    assert [p.name for p in tmp_path.iterdir()] == ["c.npz"]   # no temporary file left
    back, ex = load_checkpoint(path)
    assert back.t == st.t
    for f in ("q", "v", "qdd", "a", "lam"):
        np.testing.assert_array_equal(getattr(back, f), getattr(st, f))
        assert getattr(back, f).dtype == np.float64
    assert set(ex) == set(extra)
    for k in ("xi", "elements", "active"):
        np.testing.assert_array_equal(ex[k], extra[k])
        assert ex[k].dtype == extra[k].dtype
    assert ex["step"] == 12 and ex["h"] == 1 / 3 and ex["name"] == "sleeve"
    assert ex["history"] == {"sleeve": [0.1, 0.25]}


def test_overwrite_and_no_extra(tmp_path, rng):
    p = tmp_path / "checkpoint.npz"
    save_checkpoint(p, random_state(rng))
    st = random_state(rng, n=4, m=0)
    save_checkpoint(p, st)
    back, ex = load_checkpoint(p)
    assert ex == {}
    np.testing.assert_array_equal(back.q, st.q)
    assert back.lam.shape == (0,)


def test_bad_extra_and_foreign_file(tmp_path, rng):
    with pytest.raises(TypeError, match="cannot store"):
        save_checkpoint(tmp_path / "c.npz", random_state(rng), extra={"f": object()})
    np.savez(tmp_path / "other.npz", q=np.zeros(3))
    with pytest.raises(ValueError, match="not a flexmbs checkpoint"):
        load_checkpoint(tmp_path / "other.npz")
