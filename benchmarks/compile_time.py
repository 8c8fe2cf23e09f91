"""Compile time of the first run, per function, from numba's event API.

Each model kind runs in a fresh process with an empty numba cache (a new ``NUMBA_CACHE_DIR``;
the in-tree cache is left alone). The child records numba's events (``numba:compile`` per
dispatcher, ``numba:run_pass`` per compiler pass, ``numba:llvm_lock`` around LLVM's work) and
splits the exclusive time of every compiled function into

- typing: numba's type inference passes,
- lowering: numba's lowering to LLVM IR (its LLVM calls excluded),
- LLVM: LLVM's work under numba's LLVM lock (IR parsing, per-function and module passes after
  linking, machine code),
- other: numba's remaining passes (IR rewrites, IR-level inlining, analysis) and its own
  bookkeeping (cache writes),

and counts in how many compiled libraries (its own and its callers') a function's code is
linked and optimised again. Prints the table and the share of the first run that is compile.

    python benchmarks/compile_time.py [cantilever example1 rod ...] [--top 25] [--json FILE]

Kinds: ``cantilever`` (``flexmbs run examples/cantilever.toml --t-end 0.01``), ``example1``
(``flexmbs run examples/curved_beam_sleeve.toml --t-end 0.01``), ``rod``
(``python examples/helical_spring.py --t-end 5e-4``: a static solution, then 10 dynamic steps),
``complete`` and ``complete-rod`` (``flexmbs compile --complete cable`` / ``rod``: the complete
kernels that serve every model of one cable group / with a rod group).
``--cache DIR`` uses (and keeps) a given cache folder instead of an empty one, e.g. to time a
warm start: two runs with the same ``--cache``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

#: the checkout whose flexmbs is measured (another one, e.g. a scratch copy: COMPILE_TIME_ROOT)
ROOT = Path(os.environ.get("COMPILE_TIME_ROOT") or Path(__file__).resolve().parents[1])

KINDS = {
    "cantilever": ["flexmbs", "run", "examples/cantilever.toml", "--t-end", "0.01"],
    "example1": ["flexmbs", "run", "examples/curved_beam_sleeve.toml", "--t-end", "0.01"],
    "rod": ["examples/helical_spring.py", "--t-end", "5e-4", "--dt", "5e-5"],
    "complete": ["flexmbs", "compile", "--complete", "cable"],
    "complete-rod": ["flexmbs", "compile", "--complete", "rod"],
}


# ------------------------------------------------------------------ child: record the events
def _child(kind: str, out_json: str, out_dir: str) -> None:
    t_start = time.perf_counter()
    from numba.core import event as ev

    records: list[tuple[str, bool, float, str]] = []   # (kind, start?, time, label)

    class Listener(ev.Listener):
        def on_start(self, event: ev.Event) -> None:
            records.append((event.kind, True, time.perf_counter(), _label(event)))

        def on_end(self, event: ev.Event) -> None:
            records.append((event.kind, False, time.perf_counter(), _label(event)))

    def _label(event: ev.Event) -> str:
        d = event.data
        if event.kind == "numba:compile" and d:
            f = d["dispatcher"].py_func
            return f"{f.__module__}.{f.__qualname__}"
        if event.kind == "numba:run_pass" and d:
            return str(d["name"]).split(" [")[0]
        return ""

    listener = Listener()
    for k in ("numba:compile", "numba:run_pass", "numba:llvm_lock"):
        ev.register(k, listener)

    # LLVM's share per library: function passes before linking, module passes after linking
    # (the callees' code again), machine code
    from numba.core import codegen
    llvm_parts: dict[str, dict[str, float]] = defaultdict(lambda: defaultdict(float))

    def timed(cls: type, meth: str, part: str) -> None:
        orig = getattr(cls, meth)

        def wrapper(self, *a, **k):
            t = time.perf_counter()
            try:
                return orig(self, *a, **k)
            finally:
                llvm_parts[str(self.name)][part] += time.perf_counter() - t
        setattr(cls, meth, wrapper)

    timed(codegen.CPUCodeLibrary, "add_llvm_module", "functions")
    fn_sizes: list[tuple[str, str, int, float]] = []   # (library, function, instructions, s)
    if os.environ.get("COMPILE_TIME_IR_SIZES") == "1":
        def optimize_functions(self, ll_module):
            ll_module.data_layout = self._codegen._data_layout
            for func in ll_module.functions:
                size = sum(len(list(b.instructions)) for b in func.blocks)
                fpm, pb = self._codegen._function_pass_manager()
                t = time.perf_counter()
                fpm.run(func, pb)
                fn_sizes.append((str(self.name), func.name, size, time.perf_counter() - t))
        codegen.CPUCodeLibrary._optimize_functions = optimize_functions
    timed(codegen.CPUCodeLibrary, "_optimize_final_module", "module")
    timed(codegen.JITCodeLibrary, "_finalize_specific", "machine")

    argv = KINDS[kind]
    os.chdir(ROOT)
    sys.path.insert(0, str(ROOT))
    if argv[0] == "flexmbs":
        from flexmbs.cli import main
        assert Path(sys.modules["flexmbs"].__file__ or "").is_relative_to(ROOT)
        extra = ["--out", out_dir, "--overwrite"] if argv[1] == "run" else []
        code = main([*argv[1:], *extra, "--quiet"])
    else:
        import runpy
        sys.argv = [argv[0], *argv[1:], "--out", out_dir]
        try:
            runpy.run_path(str(ROOT / argv[0]), run_name="__main__")
            code = 0
        except SystemExit as exc:
            code = int(exc.code or 0)
    t_total = time.perf_counter() - t_start

    # exclusive time per (function, category) from the nested events
    table: dict[str, dict[str, float]] = defaultdict(lambda: defaultdict(float))
    stack: list[tuple[str, str]] = []       # (event kind, label)
    funcs: list[str] = []
    top_compile = 0.0
    compiles: dict[str, int] = defaultdict(int)
    entries: list[tuple[str, float]] = []      # compiled when called from Python
    last = None
    t0_top = 0.0
    for kind_, start, t, label in records:
        if last is not None and funcs:
            cat = "other"
            for k, lab in reversed(stack):
                if k == "numba:llvm_lock":
                    cat = "llvm"
                    break
                if k == "numba:run_pass":
                    cat = ("typing" if "type_inference" in lab else
                           "lowering" if "lowering" in lab else "other")
                    break
                if k == "numba:compile":
                    break
            table[funcs[-1]][cat] += t - last
        last = t
        if start:
            stack.append((kind_, label))
            if kind_ == "numba:compile":
                if not funcs:
                    t0_top = t
                funcs.append(label)
                compiles[label] += 1
        else:
            while stack and stack[-1][0] != kind_:   # unbalanced (an exception): drop
                stack.pop()
            if stack:
                stack.pop()
            if kind_ == "numba:compile" and funcs:
                name = funcs.pop()
                if not funcs:
                    top_compile += t - t0_top
                    entries.append((name, t - t0_top))

    # in how many compiled libraries each function's code is linked (and optimised again)
    linked: dict[str, int] = defaultdict(int)
    import gc

    from numba.core.registry import CPUDispatcher

    def lib_name(lib: object) -> str:
        return str(getattr(lib, "name", ""))

    libs_of: dict[str, str] = {}
    dispatchers = [o for o in gc.get_objects() if isinstance(o, CPUDispatcher)]
    for d in dispatchers:
        for cres in d.overloads.values():
            libs_of[lib_name(cres.library)] = f"{d.py_func.__module__}.{d.py_func.__qualname__}"
    for d in dispatchers:
        for cres in d.overloads.values():
            seen: set[int] = set()
            todo = [cres.library]
            while todo:
                lib = todo.pop()
                if id(lib) in seen:
                    continue
                seen.add(id(lib))
                name = libs_of.get(lib_name(lib))
                if name is not None:
                    linked[name] += 1
                todo.extend(getattr(lib, "_linking_libraries", ()))
    llvm: dict[str, dict[str, float]] = defaultdict(lambda: defaultdict(float))
    for lib, parts in llvm_parts.items():
        name = libs_of.get(lib)
        if name is not None:
            for k, v in parts.items():
                llvm[name][k] += v
    Path(out_json).write_text(json.dumps(dict(
        kind=kind, exit=code, total=t_total, compile=top_compile,
        table={f: dict(v) for f, v in table.items()}, compiles=dict(compiles), entries=entries,
        linked=dict(linked), llvm={f: dict(v) for f, v in llvm.items()},
        fn_sizes=[(libs_of.get(lib, lib), fn, n, t) for lib, fn, n, t in fn_sizes])))


# ------------------------------------------------------------------ parent
def measure(kind: str, cache: str | None = None) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ)
        env["NUMBA_CACHE_DIR"] = cache or os.path.join(tmp, "numba-cache")
        out_json = os.path.join(tmp, "events.json")
        t0 = time.perf_counter()
        cpu0 = _children_cpu()
        proc = subprocess.run([sys.executable, __file__, "--child", kind, out_json,
                               os.path.join(tmp, "out")], env=env, cwd=ROOT,
                              capture_output=True, text=True)
        wall = time.perf_counter() - t0
        cpu = _children_cpu() - cpu0
        if proc.returncode != 0 or not os.path.exists(out_json):
            raise SystemExit(f"{kind}: child failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
        res = json.loads(Path(out_json).read_text())
    res["wall"] = wall
    res["cpu"] = cpu
    return res


def _children_cpu() -> float:
    import resource

    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def report(res: dict, top: int) -> None:
    cats = ("typing", "lowering", "llvm", "other")
    rows = sorted(res["table"].items(), key=lambda kv: -sum(kv[1].values()))
    tot = {c: sum(v.get(c, 0.0) for _, v in rows) for c in cats}
    print(f"\n== {res['kind']}: process wall {res['wall']:.1f} s (CPU {res['cpu']:.1f} s), of "
          f"which numba compile {res['compile']:.1f} s ({100 * res['compile'] / res['wall']:.0f} %); "
          f"{len(rows)} functions compiled")
    print(f"   typing {tot['typing']:.1f} s, lowering {tot['lowering']:.1f} s, "
          f"LLVM {tot['llvm']:.1f} s, other {tot['other']:.1f} s")
    print("   called from Python (with their callees): " + ", ".join(
        f"{n.replace('flexmbs.', '')} {t:.1f}" for n, t in sorted(res["entries"], key=lambda x: -x[1])))
    ll = res.get("llvm", {})
    parts = ("functions", "module", "machine")
    lt = {p: sum(v.get(p, 0.0) for v in ll.values()) for p in parts}
    print(f"   LLVM: function passes {lt['functions']:.1f} s, module passes after linking "
          f"{lt['module']:.1f} s, machine code {lt['machine']:.1f} s")
    by_module: dict[str, float] = defaultdict(float)
    for name, v in rows:
        mod = name.rsplit(".", 1)[0] if "<locals>" not in name else name.split(".<locals>")[0]
        mod = mod.rsplit(".", 1)[0] if not mod.startswith("flexmbs") else mod
        by_module[mod] += sum(v.values())
    print("   by module: " + ", ".join(f"{m.replace('flexmbs.', '')} {t:.1f}"
                                       for m, t in sorted(by_module.items(), key=lambda x: -x[1])
                                       if t >= 0.5))
    print("| function | total s | typing | lowering | LLVM (fn / module / code) | other | "
          "compiled | linked into |")
    print("|---|---|---|---|---|---|---|---|")
    for name, v in rows[:top]:
        short = name.replace("flexmbs.", "")
        lv = ll.get(name, {})
        print(f"| {short} | {sum(v.values()):.2f} | {v.get('typing', 0.0):.2f} | "
              f"{v.get('lowering', 0.0):.2f} | {v.get('llvm', 0.0):.2f} ("
              + " / ".join(f"{lv.get(p, 0.0):.2f}" for p in parts) + f") | "
              f"{v.get('other', 0.0):.2f} | {res['compiles'].get(name, 0)} | "
              f"{res['linked'].get(name, 0)} |")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--child":
        _child(*argv[1:4])
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("kinds", nargs="*", default=["cantilever", "example1", "rod"],
                    choices=sorted(KINDS))
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--cache", default=None, help="numba cache folder (default: a new empty one)")
    ap.add_argument("--json", default=None, help="also write the raw results here")
    args = ap.parse_args(argv)
    results = []
    for kind in args.kinds:
        res = measure(kind, args.cache)
        report(res, args.top)
        results.append(res)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
