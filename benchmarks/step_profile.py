"""Where a contact-rich step goes (issue 56, item 1): counts per step, their causes, unit costs.

Three models: the guide wire (``examples/guide_wire.toml``), the 200-element wire in the
1 000-section quarter-circle tube (``tube.py``'s :func:`~tube.long_wire_model`) and the tendon
robot (``tendon_robot.py``, 20 disks). Everything goes through the public API
(:func:`flexmbs.simulate`); the integrator's stepper is instrumented from Python (no compiled
module is touched):

1. **Compiled run** (``--t-end``): ``_CompiledStepper.advance`` is called one step at a time
   (the compiled loop keeps its whole state in ``info`` between calls and the time functions
   are those of the chunk, so the steps are those of a chunked run, bit for bit) and the
   counters of ``info`` are read around each step: Newton iterations,
   factorisations (split by cause: *forced*, the step started without a factorisation — the
   driver's ``invalidate`` at a step-size change, a rejected step or a failed advance;
   *renewal*, the between-step rule ``renew_jacobian``; *in-solve*, the rule ``_slow`` on the
   contraction), residual evaluations, rejected steps and their reason. ``invalidate`` is
   counted by its caller's line. After each step the clearance joints' candidate rows (the
   last residual's) give the contact state: per section, the contacts (gap < 0) and those the
   stick law holds; the changes from the last step (onsets, releases, stick/slip switches, on
   the bore's sections and on the tip sections) are set against the step's iterations.
2. **Python run** (``--python-t-end``, shorter): ``compiled=False``; every residual of the
   step's Newton records the contact state, every contraction decision of the held matrix
   (``flexmbs.solvers.newton._too_slow``) its rate ``err / err_prev``, and whether the contact
   state changed since the last iterate and since the held matrix was factorised.
3. **Unit costs** at the compiled run's last state (compiled loops of ``unit_loops.py``, as
   ``tendon_robot.py --units``): one residual, one iteration matrix, one factorisation of the
   run's plan, one solve; the modelled step cost ``refreshes x (matrix + factorisation) +
   residuals x residual + iterations x solve`` beside the measured wall of an uninstrumented
   run of the same span.

    python benchmarks/step_profile.py --model guide_wire --t-end 0.3 --python-t-end 0.05
    python benchmarks/step_profile.py --model tube_wire --t-end 0.02 [--json out.json]
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import sys
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
if __package__ in (None, ""):      # run as a script: the checkout's flexmbs
    sys.path.insert(0, str(HERE.parent))
if str(HERE) not in sys.path:      # the other benchmarks (tube, tendon_robot, unit_loops)
    sys.path.insert(0, str(HERE))

import flexmbs as fm  # noqa: E402
from flexmbs.assembly import Assembly  # noqa: E402
from flexmbs.contact._detect import GAP_COL, N_TIPS  # noqa: E402
from flexmbs.solvers import generalized_alpha as ga  # noqa: E402
from flexmbs.solvers import newton as nw  # noqa: E402

MODELS = ("guide_wire", "tube_wire", "tendon_robot")
#: the stick flag's column of a candidate row (``_detect.COLS``: "stick")
STICK_COL = 18
#: contraction-rate bins of the held-matrix iterations
RATE_BINS = (0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0, np.inf)


@dataclass
class Case:
    """A model to profile: a fresh model per run, its step and integrator options."""

    name: str
    build: Callable[[], fm.Model]
    dt: float
    options: fm.GeneralizedAlpha


def case(name: str, disks: int = 20) -> Case:
    """The model ``name`` (:data:`MODELS`)."""
    if name == "guide_wire":
        from flexmbs.io.scenario import load_scenario

        path = HERE.parent / "examples" / "guide_wire.toml"
        sc = load_scenario(path)
        opts = sc.integrator_options()
        assert opts is not None
        return Case(name, lambda: load_scenario(path).model, sc.simulation.dt, opts)
    if name == "tube_wire":
        from tube import long_wire_model

        return Case(name, lambda: long_wire_model()[0], 1e-4, fm.GeneralizedAlpha())
    if name == "tendon_robot":
        import tendon_robot

        return Case(name, lambda: tendon_robot.build(disks)[0], 1e-3,
                    fm.GeneralizedAlpha(rho_inf=0.5))
    raise SystemExit(f"unknown model {name!r} (known: {', '.join(MODELS)})")


# ---------------------------------------------------------------- the contact state
def contact_state(asm: Assembly) -> dict[tuple[int, int], tuple[int, int, bool]]:
    """The clearance joints' contacts of the last residual: per (joint, section slot) with
    contacts, (contacts, contacts the stick law holds, a tip section)."""
    part = asm.system.clearance
    out: dict[tuple[int, int], tuple[int, int, bool]] = {}
    for j in range(int(part.n_candidates.size)):
        rows = part.rows[j, :int(part.n_candidates[j])]
        tips = int(part.n_sec[j]) - N_TIPS
        for row in rows[rows[:, GAP_COL] < 0.0]:
            k = int(row[0])
            n, s, _ = out.get((j, k), (0, 0, k >= tips))
            out[(j, k)] = (n + 1, s + int(row[STICK_COL] > 0.5), k >= tips)
    return out


def changes(old: dict, new: dict) -> dict[str, int]:
    """What changed from contact state ``old`` to ``new`` (:func:`contact_state`): contacts
    made and lost, stick/slip switches (on the sections with contacts in both), each also on
    the tip sections alone."""
    out = Counter()
    for key in old.keys() | new.keys():
        n0, s0, tip = old.get(key, (0, 0, False))
        n1, s1, tip1 = new.get(key, (0, 0, False))
        tip = tip or tip1
        d = {"onsets": max(0, n1 - n0), "releases": max(0, n0 - n1),
             "stick_slip": abs(s1 - s0) if n0 and n1 else 0}
        for k, x in d.items():
            out[k] += x
            if tip:
                out["tip_" + k] += x
    return dict(out)


def totals(state: dict) -> tuple[int, int]:
    """Contacts and stuck contacts of a :func:`contact_state`."""
    return sum(v[0] for v in state.values()), sum(v[1] for v in state.values())


@contextlib.contextmanager
def patched(obj: Any, name: str, value: Any) -> Iterator[None]:
    old = getattr(obj, name)
    setattr(obj, name, value)
    try:
        yield
    finally:
        setattr(obj, name, old)


def _caller() -> str:
    f = sys._getframe(2)
    return f"{Path(f.f_code.co_filename).name}:{f.f_lineno} ({f.f_code.co_name})"


# ---------------------------------------------------------------- 1. the compiled run
def compiled_profile(c: Case, t_end: float) -> tuple[dict, Assembly, ga.State]:
    """Counts per step of a compiled run of ``t_end`` (module docstring, 1.)."""
    asm = Assembly(c.build())
    steps: list[dict] = []
    invalidations: Counter = Counter()
    orig_advance = ga._CompiledStepper.advance
    orig_invalidate = ga._CompiledStepper.invalidate

    def invalidate(self: ga._CompiledStepper) -> None:
        invalidations[_caller()] += 1
        orig_invalidate(self)

    def advance(self: ga._CompiledStepper, h: float, n_steps: int, t0: float,
                tolerance: float = 0.0) -> int:
        cc, info = self.cc, self.info
        err_max = 0.0
        # the time functions at the chunk's step ends, as the chunked call computes them
        # (t0 + (k + 1) h, not (t0 + k h) + h: the same steps to the last bit)
        fns = self.asm.functions
        full = fns.table(t0, h, n_steps)
        for k in range(n_steps):
            have, renew = info[cc.INFO_HAVE], info[cc.INFO_RENEW]
            before = (info[cc.INFO_TOTAL], info[cc.INFO_FACT], info[cc.INFO_RES])
            rec: dict[str, Any] = {"t": t0 + k * h, "h": h, "forced": int(have == 0.0),
                                   "renewal": int(have != 0.0 and renew != 0.0)}
            fns.table = lambda *_a, row=full[k:k + 1]: row     # type: ignore[method-assign]
            try:
                orig_advance(self, h, 1, t0 + k * h, tolerance)
                rec["failed"] = ""
            except ga._StepFailure as exc:
                rec["failed"] = ("replan" if exc.replan else "step error" if exc.error
                                 else str(exc).split(" (")[0])
                raise ga._StepFailure(k + exc.done, str(exc), error=exc.error,
                                      replan=exc.replan) from None
            finally:
                del fns.table
                rec["its"] = int(info[cc.INFO_TOTAL] - before[0])
                rec["facts"] = int(info[cc.INFO_FACT] - before[1])
                rec["res"] = int(info[cc.INFO_RES] - before[2])
                rec["contacts"] = contact_state(asm)
                steps.append(rec)
            err_max = max(err_max, float(info[cc.INFO_STEP_ERR_MAX]))
            if self.stopped is not None:
                info[cc.INFO_STEP_ERR_MAX] = err_max
                return k + 1
        info[cc.INFO_STEP_ERR_MAX] = err_max
        return n_steps

    with patched(ga._CompiledStepper, "advance", advance), \
            patched(ga._CompiledStepper, "invalidate", invalidate), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(asm, t_end=t_end, dt=c.dt, output_interval=t_end, integrator=c.options,
                          record_energy=False)
    return summarise(steps, res.stats, invalidations), asm, res.final_state


def summarise(steps: list[dict], stats: ga.IntegrationStats, invalidations: Counter) -> dict:
    """The report of :func:`compiled_profile` from its per-step records; the steps are put in
    classes by the change of the contact state from the last converged step (a rejected
    attempt's counts go to ``attempts`` and the totals only)."""
    ok = [s for s in steps if not s["failed"]]
    prev: dict = {}
    by_change: dict[str, list[dict]] = {"no change": [], "stick/slip only": [],
                                        "onset or release, tip sections only": [],
                                        "onset or release": []}
    switch = Counter()
    for s in steps:
        if s["failed"]:
            continue
        d = changes(prev, s["contacts"])
        prev = s["contacts"]
        for k, x in d.items():
            switch[k] += x
        made = d.get("onsets", 0) + d.get("releases", 0)
        tips = made and made == d.get("tip_onsets", 0) + d.get("tip_releases", 0)
        key = ("onset or release, tip sections only" if tips else "onset or release" if made
               else "stick/slip only" if d.get("stick_slip", 0) else "no change")
        by_change[key].append(s)
    n = max(len(ok), 1)
    facts = sum(s["facts"] for s in steps)
    forced = sum(s["forced"] for s in steps)
    renewal = sum(s["renewal"] for s in steps)
    contacts = [totals(s["contacts"]) for s in ok]
    return {
        "steps": len(ok), "attempts": len(steps), "rejected": len(steps) - len(ok),
        "rejections": dict(Counter(s["failed"] for s in steps if s["failed"])),
        "iterations": sum(s["its"] for s in steps), "factorisations": facts,
        "residuals": sum(s["res"] for s in steps),
        "factorisations_by_cause": {"forced": forced, "renewal": renewal,
                                    "in_solve": facts - forced - renewal},
        "invalidations": dict(invalidations),
        "per_step": {k: sum(s[k] for s in steps) / n for k in ("its", "facts", "res")},
        "iterations_histogram": dict(sorted(Counter(s["its"] for s in ok).items())),
        "contacts_mean": float(np.mean([x[0] for x in contacts])) if contacts else 0.0,
        "stuck_mean": float(np.mean([x[1] for x in contacts])) if contacts else 0.0,
        "contacts_max": max((x[0] for x in contacts), default=0),
        "timeline": timeline(steps),
        "changes_between_steps": dict(switch),
        "steps_by_change": {k: {"steps": len(v),
                                "its_per_step": float(np.mean([s["its"] for s in v])) if v else 0.0,
                                "facts_per_step": float(np.mean([s["facts"] for s in v])) if v else 0.0,
                                "facts": sum(s["facts"] for s in v)}
                            for k, v in by_change.items()},
        "stats": {"steps": stats.steps, "rejected": stats.rejected_steps,
                  "iterations": stats.newton_iterations, "factorisations": stats.factorizations,
                  "residuals": stats.residual_evaluations, "replans": stats.replans},
        "step_sizes": dict(Counter(f"{s['h']:.3g}" for s in ok)),
    }


def timeline(steps: list[dict], windows: int = 5) -> dict[str, dict[str, float]]:
    """Per window of the run (``windows`` equal spans of time): steps, iterations,
    factorisations and residuals per step, mean contacts."""
    if not steps:
        return {}
    t = np.array([s["t"] for s in steps])
    edges = np.linspace(t[0], t[-1] + steps[-1]["h"], windows + 1)
    out = {}
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = [s for s in steps if a <= s["t"] < b]
        ok = [s for s in sel if not s["failed"]]
        n = max(len(ok), 1)
        out[f"{a:.4g}-{b:.4g} s"] = {
            "steps": len(ok), "rejected": len(sel) - len(ok),
            "its": sum(s["its"] for s in sel) / n, "facts": sum(s["facts"] for s in sel) / n,
            "res": sum(s["res"] for s in sel) / n,
            "contacts": float(np.mean([totals(s["contacts"])[0] for s in ok])) if ok else 0.0}
    return out


# ---------------------------------------------------------------- 2. the Python run
def python_profile(c: Case, t_end: float, t_from: float = 0.0) -> dict:
    """Contraction rates of the held matrix against contact changes (module docstring, 2.),
    from ``t_from`` (reached by a compiled run) for ``t_end``."""
    asm = Assembly(c.build())
    state = None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if t_from > 0:
            state, _ = ga.integrate(asm, c.options, t_end=t_from, dt=c.dt, output_interval=t_from)
    last: dict[str, Any] = {"state": {}, "iterate": {}, "factored": {}}
    decisions: list[dict] = []
    orig_eval = ga._AlphaStep.evaluate
    orig_factorize = nw.Newton._factorize
    orig_slow = nw._too_slow
    orig_solve = nw.Newton.solve

    solves: list[dict] = []
    last["end"], last["seen"] = {}, []

    def evaluate(self: ga._AlphaStep, want_matrix: bool) -> Any:
        out = orig_eval(self, want_matrix)
        last["iterate"], last["state"] = last["state"], contact_state(self.asm)
        last["seen"].append(last["state"])
        return out

    def factorize(self: nw.Newton, A: Any) -> None:
        last["factored"] = last["state"]
        orig_factorize(self, A)

    def too_slow(err: float, err_prev: float, o: nw.NewtonOptions) -> bool:
        slow = orig_slow(err, err_prev, o)
        d_it = changes(last["iterate"], last["state"])
        d_f = changes(last["factored"], last["state"])
        decisions.append({"rate": err / err_prev, "refresh": bool(slow),
                          "changed_since_iterate": any(d_it.values()),
                          "changed_since_factor": any(d_f.values()),
                          "made_since_factor": bool(d_f.get("onsets", 0) + d_f.get("releases", 0)),
                          "stick_slip_since_factor": bool(d_f.get("stick_slip", 0))})
        return slow

    def solve(self: nw.Newton, problem: Any, **kw: Any) -> Any:
        last["state"], last["seen"] = {}, []    # a step's first residual: no previous iterate
        f0 = self.total.factorizations
        ok = False
        try:
            out = orig_solve(self, problem, **kw)
            ok = True
            return out
        finally:
            end, seen = last["state"], last["seen"]
            solves.append({"ok": ok, "facts": self.total.factorizations - f0,
                           "end_changed": end != last["end"],
                           "predictor_other": bool(seen) and seen[0] != end,
                           "passed_other": any(x != end for x in seen[1:])})
            if ok:
                last["end"] = end

    opts = ga.GeneralizedAlpha(**{**{f: getattr(c.options, f) for f in (
        "rho_inf", "scheme", "newton", "adaptive", "min_step", "grow_after", "predictor",
        "constraint_level", "step_tolerance")}, "compiled": False})
    t0 = time.perf_counter()
    with patched(ga._AlphaStep, "evaluate", evaluate), \
            patched(nw.Newton, "_factorize", factorize), patched(nw, "_too_slow", too_slow), \
            patched(nw.Newton, "solve", solve), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, stats = ga.integrate(asm, opts, t_end=t_from + t_end, dt=c.dt, state=state,
                                output_interval=t_end)
    wall = time.perf_counter() - t0
    rates = np.array([d["rate"] for d in decisions])
    hist = np.histogram(rates, bins=RATE_BINS)[0] if rates.size else np.zeros(len(RATE_BINS) - 1)
    labels = [f"{a:g}-{b:g}" for a, b in zip(RATE_BINS[:-1], RATE_BINS[1:], strict=True)]

    def share(sel: Callable[[dict], bool], where: Callable[[dict], bool]) -> tuple[int, int]:
        pool = [d for d in decisions if where(d)]
        return sum(sel(d) for d in pool), len(pool)

    table = {}
    for name, key in (("since the last iterate", "changed_since_iterate"),
                      ("since the factorisation", "changed_since_factor"),
                      ("contacts made/lost since the factorisation", "made_since_factor"),
                      ("stick/slip since the factorisation", "stick_slip_since_factor")):
        table[name] = {label: list(share(lambda d, k=key: d[k], pool)) for label, pool in (
            ("rate > 1", lambda d: d["rate"] > 1.0), ("rate > 0.9", lambda d: d["rate"] > 0.9),
            ("rate 0.3-0.9", lambda d: 0.3 <= d["rate"] <= 0.9),
            ("rate < 0.3", lambda d: d["rate"] < 0.3),
            ("refreshed", lambda d: d["refresh"]))}
    classes: dict[str, dict[str, int]] = {}
    for sv in solves:
        key = ("failed" if not sv["ok"] else "contact state changed from the last step"
               if sv["end_changed"] else
               "same contact state, a later iterate passed through another"
               if sv["passed_other"] else "same contact state, only the predictor's differs"
               if sv["predictor_other"] else "same contact state in every iterate")
        cl = classes.setdefault(key, {"steps": 0, "facts": 0})
        cl["steps"] += 1
        cl["facts"] += sv["facts"]
    return {"t_from": t_from, "t_end": t_end, "wall_s": wall, "steps": stats.steps,
            "steps_by_contact_state": classes,
            "rejected": stats.rejected_steps, "iterations": stats.newton_iterations,
            "factorisations": stats.factorizations, "decisions": int(rates.size),
            "refreshes_decided": sum(d["refresh"] for d in decisions),
            "rate_histogram": dict(zip(labels, (int(x) for x in hist), strict=True)),
            "rate_above_1": int(np.sum(rates > 1.0)),
            "contact_change_vs_rate": table}


# ---------------------------------------------------------------- 3. unit costs
def unit_costs(asm: Assembly, state: ga.State, dt: float, repeats: int = 5) -> dict:
    """Unit costs [µs] at ``state`` with the compiled loops of ``unit_loops.py`` on the plan
    a compiled run takes (the one that follows the joints where it is much cheaper), best of
    ``repeats`` loops; ``clearance_us``: the clearance joints' terms alone (a part of the
    residual)."""
    from unit_loops import best_of, loop_clearance, loop_factorize, loop_matrix, loop_residual, loop_solve

    from flexmbs import driver
    from flexmbs.solvers.factor import FOLLOW_COST_RATIO, FOLLOW_REACH
    from flexmbs.terms import dynamic_mode

    m, mode = asm.kernel_system, dynamic_mode()
    fv = asm.functions.table(state.t, dt, 1)[0]
    r = np.zeros(asm.n_total)
    x = np.zeros_like(r)
    data = np.zeros_like(asm.matrix.data)
    plan = asm.factor_plan()
    windows = asm.contact_windows(FOLLOW_REACH)
    if windows is not None:
        following = asm.factor_plan(windows=windows)
        if following.cost < FOLLOW_COST_RATIO * plan.cost:
            asm.follow(windows)
            plan = asm.factor_plan(windows=windows)
    q, v, qdd, lam = state.q, state.v, state.qdd, state.lam
    driver.jacobian(m, q, v, qdd, lam, fv, mode, 1.0, 0.05, 1e-8, data)
    lu = plan.factorization(asm.matrix)
    lu.factorize(data)
    n = max(5, min(200, int(2e5 / asm.n_total)))
    out = {"unknowns": int(asm.n_total),
           "matrix_us": best_of(loop_matrix, (m, q, v, qdd, lam, fv, mode, data), n, repeats),
           "residual_us": best_of(loop_residual, (m, q, v, qdd, lam, fv, mode, r), n, repeats),
           "factor_us": best_of(loop_factorize, (lu.factor, data), n, repeats),
           "solve_us": best_of(loop_solve, (lu.factor, r, x), n, repeats),
           # the clearance joints' share of the residual (detection and contact forces)
           "clearance_us": best_of(loop_clearance, (m.clearance, q, v, r, np.zeros(4, np.int64)),
                                   n, repeats)}
    asm.follow(None)
    return out


def wall_per_step(c: Case, t_end: float) -> dict:
    """An uninstrumented compiled run of ``t_end``: wall [s] from its first output (set-up
    excluded) to its end, and its counts."""
    asm = Assembly(c.build())
    start: list[float] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fm.simulate(asm, t_end=t_end, dt=c.dt, output_interval=t_end, integrator=c.options,
                          record_energy=False,
                          observer=lambda _s: start.append(time.perf_counter()))
        wall = time.perf_counter() - start[0]
    s = res.stats
    return {"wall_s": wall, "steps": s.steps, "iterations": s.newton_iterations,
            "factorisations": s.factorizations, "residuals": s.residual_evaluations,
            "ms_per_step": 1e3 * wall / max(s.steps, 1)}


def modelled(counts: dict, units: dict) -> dict:
    """Modelled cost [ms per step] of the counts per step with the unit costs."""
    n = max(counts["steps"], 1)
    parts = {"refreshes": counts["factorisations"] / n * (units["matrix_us"] + units["factor_us"]),
             "residuals": counts["residuals"] / n * units["residual_us"],
             "solves": counts["iterations"] / n * units["solve_us"]}
    return {k: v / 1e3 for k, v in parts.items()} | {"total": sum(parts.values()) / 1e3}


def with_newton(c: Case, settings: list[str]) -> Case:
    """``c`` with Newton options changed by ``name=value`` settings (``refresh_ratio=0.9``)."""
    if not settings:
        return c
    kw = {}
    for item in settings:
        name, _, value = item.partition("=")
        kw[name] = type(getattr(c.options.newton, name))(float(value))
    newton = dataclasses.replace(c.options.newton, **kw)
    return dataclasses.replace(c, options=dataclasses.replace(c.options, newton=newton))


def profile(model: str, t_end: float, python_t_end: float = 0.0, units: bool = True,
            wall: bool = True, disks: int = 20, python_from: float | None = None,
            newton: list[str] | None = None) -> dict:
    """The whole report of one model (module docstring); ``newton``: Newton options changed
    (:func:`with_newton`)."""
    c = with_newton(case(model, disks), newton or [])
    fm.simulate(c.build(), t_end=2 * c.dt, dt=c.dt, output_interval=2 * c.dt,
                integrator=c.options, record_energy=False)      # kernels loaded or compiled
    report: dict[str, Any] = {"model": model, "t_end": t_end, "dt": c.dt,
                              "newton": dataclasses.asdict(c.options.newton)}
    t0 = time.perf_counter()
    report["compiled"], asm, state = compiled_profile(c, t_end)
    report["compiled"]["instrumented_wall_s"] = time.perf_counter() - t0
    if wall:
        report["wall"] = w = wall_per_step(c, t_end)
        cs = report["compiled"]["stats"]
        w["same_counts"] = all(w[k] == cs[k] for k in ("steps", "iterations", "factorisations",
                                                       "residuals"))
    if units:
        report["units"] = unit_costs(asm, state, c.dt)
        report["model_ms_per_step"] = modelled(report["compiled"], report["units"])
    if python_t_end > 0:
        report["python"] = python_profile(
            c, python_t_end, max(0.0, t_end - python_t_end) if python_from is None else python_from)
    return report


def _fmt(d: Any, indent: int = 0) -> str:
    pad = "  " * indent
    if isinstance(d, dict):
        return "\n".join(f"{pad}{k}:" + ("\n" + _fmt(v, indent + 1) if isinstance(v, dict)
                                         else f" {_fmt(v)}") for k, v in d.items())
    if isinstance(d, float):
        return f"{d:.4g}"
    return str(d)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", choices=MODELS, default="guide_wire")
    ap.add_argument("--t-end", type=float, default=0.3, help="compiled run [s]")
    ap.add_argument("--python-t-end", type=float, default=0.0,
                    help="Python-stepper run for the contraction rates [s] (0: none)")
    ap.add_argument("--python-from", type=float, default=None,
                    help="its start, reached compiled [s] (default: t_end - python_t_end)")
    ap.add_argument("--disks", type=int, default=20, help="tendon robot's disks")
    ap.add_argument("--no-units", action="store_true", help="skip the unit costs")
    ap.add_argument("--no-wall", action="store_true", help="skip the uninstrumented run")
    ap.add_argument("--newton", action="append", default=[], metavar="NAME=VALUE",
                    help="a Newton option changed (NewtonOptions), e.g. retreats=4")
    ap.add_argument("--json", type=Path, help="write the report here too")
    a = ap.parse_args(argv)
    rep = profile(a.model, a.t_end, a.python_t_end, units=not a.no_units, wall=not a.no_wall,
                  disks=a.disks, python_from=a.python_from, newton=a.newton)
    print(_fmt(rep))
    if a.json:
        a.json.write_text(json.dumps(rep, indent=1, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
