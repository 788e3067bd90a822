"""A benchmark's results file: ``benchmarks/results/NAME.json``, what the docs quote timings
from (tests/docnumbers/ reads its ``numbers``; tests/test_doc_numbers.py checks the pages
against them). Each file says when, on which machine, at which commit and under which load
it was measured, since a timing means nothing without them.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"
#: The CPU flags a result file records: what picks numpy's BLAS kernels (docs/reproducibility.md).
VECTOR_EXTENSIONS = ("sse4_2", "avx", "avx2", "fma", "avx512f")


def machine() -> dict:
    """The machine as far as a timing or a last bit depends on it (CPU model and the vector
    extensions that pick numpy's BLAS kernels, cores this process may use, memory, the
    system)."""
    model, flags = None, []
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name") and model is None:
                model = line.split(":", 1)[1].strip()
            if line.startswith("flags") and not flags:
                flags = line.split(":", 1)[1].split()
    except OSError:
        pass
    memory = None
    try:
        memory = int(Path("/proc/meminfo").read_text().split()[1]) * 1024
    except (OSError, IndexError, ValueError):
        pass
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {"cpu": model or platform.processor(),
            "vector_extensions": [f for f in VECTOR_EXTENSIONS if f in flags], "cores": cores,
            "memory_bytes": memory,
            "system": f"{platform.system()} {platform.release()}",
            "python": platform.python_version()}


def load_average() -> list | None:
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:
        return None


def write(name: str, numbers: dict, details: dict | None = None, *, started_load=None,
          out: Path | None = None) -> Path:
    """Write ``results/NAME.json`` (or ``out``): the flat ``numbers`` the docs may quote
    (a number, or [low, high] for a range over repeats or cases), the ``details`` behind
    them, and when, where, at which commit and under which load they were measured."""
    from treeimpact.compare.runs.provenance import code_version, environment

    path = Path(out) if out else RESULTS / f"{name}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    data = {"benchmark": f"benchmarks/{Path(sys.argv[0]).name}", "argv": sys.argv[1:],
            "measured": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "machine": machine(), "load_average": {"start": started_load,
                                                   "end": load_average()},
            "code": code_version(), "environment": environment(),
            "numbers": numbers, "details": details or {}}
    path.write_text(json.dumps(data, indent=1) + "\n")
    print(f"wrote {path}")
    return path


def span(values) -> list:
    """[min, max] of the values (a range quoted as low-high)."""
    values = list(values)
    return [min(values), max(values)]
