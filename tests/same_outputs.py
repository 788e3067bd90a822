"""Whether two output folders of treeimpact hold the same results (issue 42 item 6).

``python -m tests.same_outputs BEFORE AFTER`` compares every file the two folders share and
names the files only one has:

* JSON (report.json, sweep.json, ...): the same keys and the same values, floats bit for bit,
  after dropping what a second run of the same code changes too (:data:`VOLATILE`: wall
  times, the commit, the date, the machine's load);
* CSV and Parquet tables: the same columns and cells (pandas), the volatile columns dropped
  and the rows in one order (a sweep writes its points as its workers finish them);
* PNG figures: the same bytes (matplotlib writes no date into a PNG);
* report.md / report.html: not compared, they render report.json with its wall times.

Prints one line per difference (at most 40 a file) and exits 0 when there is none, 1
otherwise, 2 on a bad argument. Tooling, not installed.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import pandas as pd

#: Keys and columns that differ between two runs of the same code on the same machine:
#: measured times (a study's mean wall time per run, the design map's CPU per cell), which
#: worker or task ran a point, when it finished or was generated, the
#: commit and load.
VOLATILE = frozenset({"wall_s", "stepping_s", "swing_s", "step_us", "git_commit", "git_dirty",
                      "measured", "generated", "load_average", "worker", "task",
                      "finished", "mean_wall_s", "cpu_s_per_cell"})
RENDERED = frozenset({".md", ".html"})
MAX_LINES = 40


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    return type(a) is type(b) and a == b


def json_differences(a, b, path: str = "") -> list:
    """Where two loaded JSON documents differ (paths like ``/runs/runs[3]/x_max``), the keys
    of :data:`VOLATILE` skipped at any depth."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for key in sorted(set(a) | set(b)):
            if key in VOLATILE or path.endswith("/wall_s"):
                continue
            if key not in a or key not in b:
                out.append(f"{path}/{key}: only in {'after' if key in b else 'before'}")
            else:
                out += json_differences(a[key], b[key], f"{path}/{key}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} items before, {len(b)} after"]
        return [d for i, (x, y) in enumerate(zip(a, b))
                for d in json_differences(x, y, f"{path}[{i}]")]
    return [] if _same(a, b) else [f"{path}: {a!r} before, {b!r} after"]


def table_differences(before: Path, after: Path) -> list:
    """Where two CSV or Parquet tables differ: columns, then cells (NaN equal to NaN)."""
    if before.suffix == ".parquet":
        a, b = (pd.read_parquet(p) for p in (before, after))
    else:  # pandas 3's parser returns the float each cell's text was written from, bit for bit
        a, b = (pd.read_csv(p) for p in (before, after))
    a, b = (_canonical(t.drop(columns=[c for c in t.columns if c in VOLATILE])) for t in (a, b))
    if list(a.columns) != list(b.columns) or a.shape != b.shape:
        return [f"columns or shape: {list(a.columns)} {a.shape} before, "
                f"{list(b.columns)} {b.shape} after"]
    out = []
    for column in a.columns:
        for row, (x, y) in enumerate(zip(a[column], b[column])):
            if not (_missing(x) and _missing(y)) and (_missing(x) or _missing(y)
                                                       or not x == y):
                out.append(f"row {row} {column}: {x!r} before, {y!r} after")
    return out


def _missing(value) -> bool:
    """Whether a cell is missing (NaN, None or pandas' NA, whose ``==`` is not a bool)."""
    return pd.api.types.is_scalar(value) and bool(pd.isna(value))


def _canonical(table: pd.DataFrame) -> pd.DataFrame:
    """The table's rows sorted by their text (the order of finishing workers dropped)."""
    text = pd.Series(["\x1f".join(map(repr, row)) for row in table.itertuples(index=False)],
                     index=table.index)
    order = text.sort_values(kind="stable").index
    return table.loc[order].reset_index(drop=True)


def file_differences(before: Path, after: Path) -> list:
    """Where two files of the same name differ, by their kind (see the module's docstring)."""
    if before.suffix == ".json":
        return json_differences(*(json.loads(p.read_text()) for p in (before, after)))
    if before.suffix in (".csv", ".parquet"):
        return table_differences(before, after)
    return [] if before.read_bytes() == after.read_bytes() else ["bytes differ"]


def compare(before: Path, after: Path) -> list:
    """Every difference between two output folders, one line each, file by file."""
    files = {p.relative_to(root) for root in (before, after) for p in root.rglob("*")
             if p.is_file()}
    out = []
    for rel in sorted(files):
        if rel.suffix in RENDERED:
            continue
        if not (before / rel).exists() or not (after / rel).exists():
            out.append(f"{rel}: only {'after' if (after / rel).exists() else 'before'}")
            continue
        found = file_differences(before / rel, after / rel)
        out += [f"{rel}: {d}" for d in found[:MAX_LINES]]
        if len(found) > MAX_LINES:
            out.append(f"{rel}: ... {len(found) - MAX_LINES} more")
    return out


def main(argv: list) -> int:
    """The command: ``BEFORE AFTER``; exit 0 same, 1 different, 2 bad arguments."""
    if len(argv) != 2 or not all(Path(a).is_dir() for a in argv):
        print("usage: python -m tests.same_outputs BEFORE_DIR AFTER_DIR (two existing folders)",
              file=sys.stderr)
        return 2
    found = compare(Path(argv[0]), Path(argv[1]))
    for line in found:
        print(line)
    print(f"{'the same' if not found else f'{len(found)} differences'} "
          f"(report.md/html not compared: they render report.json)", file=sys.stderr)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
