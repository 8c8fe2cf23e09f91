"""The step profile (benchmarks/step_profile.py, issue 56 item 1) in a quick form: a few
steps of the guide wire, compiled and on the Python stepper; the report's structure and the
consistency of its counts with the integrator's. Not a timing test."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks import step_profile


def test_step_profile_counts_agree_with_the_integrator(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "profile.json"
    assert step_profile.main(["--model", "guide_wire", "--t-end", "0.006", "--python-t-end",
                              "0.002", "--python-from", "0", "--no-units", "--no-wall",
                              "--json", str(out)]) == 0
    assert "factorisations_by_cause" in capsys.readouterr().out
    rep = json.loads(out.read_text(encoding="utf-8"))
    c = rep["compiled"]
    stats = c["stats"]
    # the per-step records add up to the integrator's own counters
    assert (c["steps"], c["rejected"], c["iterations"], c["factorisations"], c["residuals"]) == (
        stats["steps"], stats["rejected"], stats["iterations"], stats["factorisations"],
        stats["residuals"])
    assert c["steps"] == 30 and c["attempts"] == c["steps"] + c["rejected"]
    causes = c["factorisations_by_cause"]
    assert min(causes.values()) >= 0 and sum(causes.values()) == c["factorisations"]
    assert causes["forced"] >= 1                      # the first step has no factorisation
    assert causes["forced"] <= sum(c["invalidations"].values())
    assert c["factorisations"] <= c["iterations"] + causes["forced"] + c["rejected"]
    assert c["residuals"] >= c["iterations"] + c["steps"]
    assert sum(c["iterations_histogram"].values()) == c["steps"]
    assert sum(w["steps"] for w in c["timeline"].values()) == c["steps"]
    assert sum(v["steps"] for v in c["steps_by_change"].values()) == c["steps"]
    assert c["contacts_max"] >= c["contacts_mean"] >= c["stuck_mean"] >= 0
    p = rep["python"]
    assert p["steps"] == 10 and p["decisions"] == sum(p["rate_histogram"].values())
    classes = p["steps_by_contact_state"].values()
    assert sum(k["steps"] for k in classes) == p["steps"] + p["rejected"]
    assert sum(k["facts"] for k in classes) == p["factorisations"]
    assert 0 <= p["refreshes_decided"] <= p["decisions"] <= p["iterations"]
    for row in p["contact_change_vs_rate"].values():
        for hits, pool in row.values():
            assert 0 <= hits <= pool <= p["decisions"]
    assert "units" not in rep and "wall" not in rep
