"""The checks of a run (docs/design.md, "The checks of a run"): the energy balance and the
constraint drift against stated bounds, in summary.json, in ``Result.extra["checks"]`` and as
one warning line each."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import flexmbs as fm
from flexmbs.assembly import Assembly
from flexmbs.checks import (
    ENERGY_BOUND,
    POSITION_DRIFT_BOUND,
    VELOCITY_DRIFT_BOUND,
    EnergyFlows,
    RunChecks,
    energy_flows,
)
from flexmbs.cli import main
from flexmbs.constraints.interaction import Interaction
from flexmbs.elements.rigid_body import pdot_from_omega_global
from flexmbs.errors import FlexmbsWarning
from tests.physics.test_rigid_dynamics import _heavy_top

ROOT = Path(__file__).resolve().parents[1]
TOP = str(ROOT / "tests" / "data" / "heavy_top.toml")
DT = 5e-4


def _top(level: str, rho_inf: float, steps: int, **kw):
    model, top, _ = _heavy_top()
    opts = fm.GeneralizedAlpha(rho_inf=rho_inf, adaptive=False, constraint_level=level)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = fm.simulate(model, t_end=steps * DT, dt=DT, output_interval=DT, integrator=opts,
                          **kw)
    said = [str(w.message) for w in caught
            if issubclass(w.category, FlexmbsWarning) and "not trusted" in str(w.message)]
    return res, said


def test_the_heavy_top_at_rho_inf_one_is_not_trusted_and_with_the_corrector_it_is():
    """Index-3 at rho_inf = 1: the period-2 mode of the joint grows (test_velocity_corrector):
    within 1 500 steps the velocity drift reaches the top's speed and the energy changes by
    1.4 %. With the velocity corrector both stay far below their bounds, and so does the
    drift at rho_inf = 0.8 (the energy is then only checked for gains)."""
    res, said = _top("position", 1.0, 1500)
    c = res.extra["checks"]
    assert c["energy"]["quantity"] == "energy change"
    assert c["energy"]["value"] > ENERGY_BOUND and not c["energy"]["passed"]
    assert c["velocity_drift"]["value"] > 0.5 and not c["velocity_drift"]["passed"]
    assert c["position_drift"]["passed"]          # Newton holds Phi at every step
    assert len(said) == 2 and said == c["warnings"]
    assert "total energy changed by" in said[0] and "Phi_q v + Phi_t" in said[1]

    # the first 500 steps of the same run are still within the bounds
    early, said = _top("position", 1.0, 500)
    assert early.extra["checks"]["velocity_drift"]["value"] < VELOCITY_DRIFT_BOUND and not said

    fixed, said = _top("position_velocity", 1.0, 1500)
    c = fixed.extra["checks"]
    assert not said and c["warnings"] == []
    assert c["velocity_drift"]["value"] < 1e-10
    assert c["energy"]["value"] < 1e-3
    damped, said = _top("position", 0.8, 1500)
    c = damped.extra["checks"]
    assert not said and c["energy"]["quantity"] == "energy gained"
    assert c["energy"]["dissipated_by"] == ["numerical damping (rho_inf = 0.8)"]
    assert c["velocity_drift"]["value"] < 1e-2 * VELOCITY_DRIFT_BOUND      # 2.0e-5 measured


def test_the_drifts_are_the_violation_of_the_joint():
    """A spherical joint moved by 1 mm and given a velocity along its constraint: the position
    drift is 1 mm over L and the velocity drift the whole speed; a rigid rotation about the
    fixed point has no velocity drift."""
    model, top, arm = _heavy_top(omega_spin=0.0)
    asm = Assembly(model)
    q, v = asm.initial_state()
    d = asm.body_dofs(top)
    checks = RunChecks(asm, rho_inf=1.0, dt=DT)
    q = q.copy()
    q[d[0]] += 1e-3
    v = np.zeros_like(v)
    v[d[:3]] = (0.7, 0.0, 0.0)
    checks.observe(q, v, 0.0, None)
    r = checks.report()
    assert r["position_drift"]["value"] == pytest.approx(1e-3 / asm.length_scale, rel=1e-9)
    assert r["velocity_drift"]["value"] == pytest.approx(1.0, rel=1e-9)
    assert r["position_drift"]["value"] > POSITION_DRIFT_BOUND and len(r["warnings"]) == 2
    assert r["energy"]["checked"] is False and "energies not evaluated" in r["energy"]["reason"]

    q0, _ = asm.initial_state()
    omega = np.array([3.0, 0.0, 0.0])            # about the fixed point at the origin
    v = np.zeros_like(q0)
    v[d[:3]] = np.cross(omega, q0[d[:3]])
    v[d[3:]] = pdot_from_omega_global(q0[d[3:]], omega)
    fresh = RunChecks(asm, rho_inf=1.0, dt=DT)
    fresh.observe(q0, v, 0.0, None)
    rep = fresh.report()
    assert rep["velocity_drift"]["value"] < 1e-12 and rep["position_drift"]["value"] < 1e-12


class _Undeclared(Interaction):
    name = "mine"


def test_what_does_work_or_dissipates_is_named():
    model, top, _ = _heavy_top()
    assert energy_flows(model, 1.0) == EnergyFlows((), (), ())
    model.add_point_load(top, (0.0, 0.0, 1.0), name="push")
    model.add_spring_damper(top, fm.GROUND, stiffness=1.0, damping=0.5, name="damper",
                            point_b=(0.0, 0.5, 0.0))
    model.interactions.append(_Undeclared())
    flows = energy_flows(model, 0.9)
    assert flows.works == ("load 'push'",)
    assert flows.dissipates == ("spring 'damper' damping", "numerical damping (rho_inf = 0.9)")
    assert flows.undeclared == ("joint 'mine'",)


def test_a_resumed_run_reports_the_checks_of_the_whole_run(tmp_path):
    whole, _ = _top("position", 1.0, 1200, out=tmp_path / "whole")
    _top("position", 1.0, 700, out=tmp_path / "part")
    model, _, _ = _heavy_top()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlexmbsWarning)
        fm.simulate(model, t_end=1200 * DT, dt=DT, output_interval=DT, out=tmp_path / "part",
                    resume=True, integrator=fm.GeneralizedAlpha(rho_inf=1.0, adaptive=False))
    a = json.loads((tmp_path / "whole" / "summary.json").read_text())["checks"]
    b = json.loads((tmp_path / "part" / "summary.json").read_text())["checks"]
    assert b == a
    assert a == json.loads(json.dumps(whole.extra["checks"]))
    assert a["velocity_drift"]["value"] > 1e-3            # the part after the resume counts


def test_the_cli_warns_in_one_line_each_and_writes_the_checks(tmp_path, capsys):
    out = tmp_path / "top"
    assert main(["run", TOP, "--out", str(out), "-q"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    trusted = [line for line in err if "not trusted" in line]
    assert [line.split(":")[0] for line in trusted] == ["flexmbs"] * 2
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert [f"flexmbs: warning: {w}" for w in summary["checks"]["warnings"]] == trusted
    assert main(["run", TOP, "--out", str(out), "-q", "--overwrite",
                 "--set", 'simulation.constraint_level="position_velocity"']) == 0
    assert not [line for line in capsys.readouterr().err.splitlines() if "not trusted" in line]
    assert json.loads((out / "summary.json").read_text())["checks"]["warnings"] == []
