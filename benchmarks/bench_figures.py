"""The report's figures saved by an earlier commit's code and today's, interleaved (issue 39
item 3: make report's work that is not physics). A benchmark, not a test.

Run: ``.venv/bin/python benchmarks/bench_figures.py [--rev 25cfad1] [--rounds 5]
[--scenario central-leader ...]``. The ladders' runs (engines included) are made once with
today's code and pickled into a temporary folder; each snippet, in a fresh process of the old
tree or today's, loads them, draws a scenario section's four figures (compare.report.figures)
and saves them as the report does (FigureFiles: titles fitted, then savefig), timing the
saving alone; it returns each PNG's SHA-256, so the run also shows the files are the same
bytes. Writes ``benchmarks/results/figures.json``; every temporary folder is removed.
"""

from __future__ import annotations

import argparse
import os
import pickle
import statistics
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent))
import _baseline  # noqa: E402
import _results  # noqa: E402

SNIPPET = r"""
import hashlib, json, pickle, sys, tempfile, time
from pathlib import Path
import matplotlib
matplotlib.use("Agg")
from treeimpact.compare.tree.ladder import build_ladder
from treeimpact.compare.report import figures as F
from treeimpact.compare.report.scenario import energy_ledger
cache = pickle.load(open(CACHE, "rb"))
save_s, digests = 0.0, {}
with tempfile.TemporaryDirectory() as tmp:
    for name in TREES:
        L = build_ladder(name, cache=cache)
        drawn = {"displacement": F.displacement_figure(L), "force": F.force_figure(L),
                 "sequence": F.sequence_figure(L)}
        led = {r.rung.id: energy_ledger(r) for r in L.rungs}
        led = {k: {**v, "style": F.rung_style(L[k].rung)} for k, v in led.items() if v}
        if led:
            drawn["energy"] = F.energy_figure(led, next(iter(led.values()))["initial"], L.name)
        sink = F.FigureFiles(Path(tmp))
        for stem, fig in drawn.items():
            t0 = time.perf_counter()
            rel = sink(fig, f"{name}-{stem}")
            save_s += time.perf_counter() - t0
            digests[rel] = hashlib.sha256((Path(tmp) / Path(rel).name).read_bytes()).hexdigest()
print(json.dumps({"save_s": save_s, "digests": digests}))
"""


def _cache(trees: list, folder: Path) -> Path:
    """Every rung of the trees' ladders run once (today's code), pickled into ``folder``."""
    from treeimpact.compare.runs.cache import RunCache
    from treeimpact.compare.tree.ladder import prefetch_ladders

    cache = RunCache()
    prefetch_ladders(cache, trees)
    path = folder / "cache.pkl"
    path.write_bytes(pickle.dumps(cache))
    return path


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rev", default="25cfad1", help="the old code's git revision")
    p.add_argument("--rounds", type=int, default=5, help="snippets per side")
    p.add_argument("--scenario", action="append", help="shipped tree (default central-leader)")
    args = p.parse_args(argv)
    trees = args.scenario or ["central-leader"]
    load = _results.load_average()
    with tempfile.TemporaryDirectory(prefix="bench-figures-") as tmp, \
            _baseline.baseline_tree(args.rev) as old:
        code = f"CACHE = {str(_cache(trees, Path(tmp)))!r}\nTREES = {trees!r}\n" + SNIPPET
        out = _baseline.interleaved(code, {"old": old, "new": None}, args.rounds)
    med = {k: statistics.median(o["save_s"] for o in v) for k, v in out.items()}
    same = all(o["digests"] == out["old"][0]["digests"] for v in out.values() for o in v)
    figures = len(out["old"][0]["digests"])
    print(f"saving {figures} figures: old {med['old']:.2f} s, new {med['new']:.2f} s "
          f"(median of {args.rounds}), new/old {med['new'] / med['old']:.2f}; "
          f"same PNG bytes in every snippet: {same}")
    _results.write("figures", {"figures.count": figures, "figures.old_save_s": round(
        med["old"], 2), "figures.new_save_s": round(med["new"], 2), "figures.ratio": round(
        med["new"] / med["old"], 2), "figures.same_bytes": same},
        {"rev": args.rev, "trees": trees, "rounds": args.rounds,
         "save_s": {k: [o["save_s"] for o in v] for k, v in out.items()}},
        started_load=load)
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
