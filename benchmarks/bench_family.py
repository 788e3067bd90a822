"""The family of trees (compare/tree/family.py, issue 50 item 8) at full size: what each member
produces on every command a user runs (a benchmark, not a test: nothing is asserted).

Run: ``nice -n 5 .venv/bin/python benchmarks/bench_family.py [--count 30] [--no-report]``.
For each member, into a temporary folder removed afterwards:

1. its regime as the exact solver found it (compare.tree.family.regime);
2. ``treeimpact simulate`` on every backend (and the beam's Timoshenko theory) at the
   backends' default sizes (the segment rule's chain, the beam's default mesh): exit code,
   the metrics or the one-line refusal, wall time;
3. one ``pytest compare`` session over every member that the paper's model can run (the
   cut member is refused at once: its exit and line recorded): per member the cross-checks
   passed, skipped (with their reasons) and failed (test ids), the session's wall time;
4. the design map (``design_map``, ``--count`` values an input): its tree's own sentence,
   the choice in the designer's units, how many sentences, wall time;
5. ``treeimpact report`` over every member with the first member's design map as its
   study: exit code, stderr, wall time (skipped with ``--no-report``).

Writes ``benchmarks/results/family.json``.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results  # noqa: E402

#: simulate's backends at their default sizes.
BACKENDS = {"analytic": [], "soft": [], "beam": [], "timoshenko": ["--beam-theory", "timoshenko"],
            "mujoco": [], "bullet": []}
CLI = [sys.executable, "-m", "treeimpact.compare.interface.cli"]


def _simulate(path: Path) -> dict:
    """Every backend's run of the member's file: exit, metrics or refusal, wall time (s)."""
    out = {}
    for name, extra in BACKENDS.items():
        backend = "beam" if name == "timoshenko" else name
        t = time.perf_counter()
        proc = subprocess.run([*CLI, "simulate", str(path), "--json", "--backend", backend,
                               *extra], capture_output=True, text=True)
        row = {"exit": proc.returncode, "wall_s": time.perf_counter() - t}
        if proc.returncode == 0:
            row["metrics"] = json.loads(proc.stdout)["metrics"]
        else:
            row["refusal"] = proc.stderr.strip()
        out[name] = row
    return out


def _compare(paths: dict, refused: set) -> dict:
    """One pytest compare session over the members not refused: per member its passed,
    skipped and failed cross-checks."""
    args = [a for n, p in paths.items() if n not in refused for a in ("--scenario", str(p))]
    t = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "pytest", "compare", *args, "-q", "-rA",
                           "-p", "no:xdist", "-p", "no:cacheprovider"],
                          capture_output=True, text=True)
    wall = time.perf_counter() - t
    text = proc.stdout
    out = {"exit": proc.returncode, "wall_s": wall,
           "summary": text.strip().splitlines()[-1] if text.strip() else ""}
    for name in paths:
        if name in refused:
            continue
        tag = re.escape(name)
        skips = [(int(n), why) for n, why in re.findall(
            rf"^SKIPPED \[(\d+)\] \S+: {tag} (.*)$", text, re.M)]  # -rA groups equal skips
        out[name] = {
            "passed": len(re.findall(rf"^PASSED \S+\[{tag}-", text, re.M)),
            "skipped": sum(n for n, _ in skips), "skip_reasons": skips,
            "failed": re.findall(rf"^FAILED \S+::(\w+\[{tag}-[^\]]*\])", text, re.M)}
    return out


def _refused_by_compare(path: Path) -> dict:
    proc = subprocess.run([sys.executable, "-m", "pytest", "compare", "--scenario", str(path),
                           "-q", "-p", "no:xdist", "-p", "no:cacheprovider"],
                          capture_output=True, text=True)
    return {"exit": proc.returncode, "line": (proc.stdout + proc.stderr).strip()[-400:]}


def _design(path: Path, folder: Path, count: int) -> dict:
    import treeimpact as ti

    t = time.perf_counter()
    try:
        paths = ti.design_map(folder, str(path), count=count)
    except Exception as exc:  # recorded, not raised: the benchmark records what each gives
        return {"error": f"{type(exc).__name__}: {exc}", "wall_s": time.perf_counter() - t}
    data = json.loads(Path(paths["json"]).read_text())
    choice = data.get("choice_at_point")
    return {"wall_s": time.perf_counter() - t, "at_point": data["at_point"],
            "choice": choice.get("text") if isinstance(choice, dict) else choice,
            "cell": data["cell"],
            "sentences": sum(len(p["sentences"]) for p in data["pairs"])}


def _report(paths: dict, study: Path, folder: Path) -> dict:
    args = [a for p in paths.values() for a in ("--scenario", str(p))]
    t = time.perf_counter()
    proc = subprocess.run([*CLI, "report", *args, "--study", str(study), "--out", str(folder)],
                          capture_output=True, text=True)
    return {"exit": proc.returncode, "stderr": proc.stderr.strip()[-1000:],
            "wall_s": time.perf_counter() - t}


def main() -> None:
    from treeimpact.compare.tree import family as F

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--count", type=int, default=30, help="design map values an input")
    ap.add_argument("--no-report", action="store_true")
    args = ap.parse_args()
    load = _results.load_average()
    members = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        paths = F.write_family(tmp / "trees")
        for member, scen, regime in F.family():
            members[member.name] = {"why": member.why, "regime": regime.label(),
                                    "regime_fields": regime.__dict__,
                                    "t_end_s": scen.t_end, "impactor": member.impactor.value,
                                    "simulate": _simulate(paths[member.name])}
            print(member.name, regime.label(), flush=True)
        refused = {n for n, m in members.items() if m["simulate"]["analytic"]["exit"] != 0}
        compare = _compare(paths, refused)
        for name in paths:
            members[name]["compare"] = (_refused_by_compare(paths[name]) if name in refused
                                        else compare[name])
            members[name]["design"] = _design(paths[name], tmp / "design" / name, args.count)
            print(name, "compared, mapped", flush=True)
        report = None if args.no_report else _report(paths, tmp / "design" / next(iter(paths)),
                                                     tmp / "report")
    numbers = {"members": len(members),
               "compare_wall_s": round(compare["wall_s"], 1),
               "compare_failed": sum(len(m["compare"].get("failed", [])) for m in members.values())}
    details = {"members": members, "compare_session": {k: compare[k] for k in
                                                       ("exit", "wall_s", "summary")},
               "report": report, "design_count": args.count}
    print(_results.write("family", numbers, details, started_load=load))


if __name__ == "__main__":
    main()
