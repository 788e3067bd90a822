"""The library's own BLAS thread limit (analytic.threads, docs/reproducibility.md "BLAS
threads"): one thread inside every public call, seen from deep inside a beam run (a spy on
numpy.linalg.eig as the beam's modal decomposition calls it), the caller's own setting back
after it; through the API, the command line in a process without OPENBLAS_NUM_THREADS, a
local pool worker and a Dask worker. Not timed: the speed is benchmarks/bench_threads.py's.

The caller's setting here is 2 threads set with threadpoolctl (conftest.py starts the tests
at 1, so 1 inside tells the limit from the caller's only when the caller's is not 1)."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg  # noqa: F401 - scipy's own BLAS loaded before the caller sets its limit
from threadpoolctl import threadpool_limits

from treeimpact.analytic import threads

CALLER = 2  # the caller's own BLAS threads in these tests: anything but threads.THREADS


def _blas_counts() -> list[int]:
    """Every loaded BLAS library's thread count as threadpoolctl reports it (a fresh scan,
    not the library's cached controllers)."""
    from threadpoolctl import threadpool_info

    return sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")


def _fresh_scenario():
    """central-leader with a trunk 1 um longer: no cached beam (continuum.beam's lru_cache)
    spares the run its eigen-decomposition."""
    import treeimpact as ti

    s = ti.load_scenario("central-leader")
    length = s.trunk.length + 1e-6 * (1 + len(_SEEN))
    _SEEN.append(length)
    return dataclasses.replace(s, trunk=dataclasses.replace(s.trunk, length=length))


_SEEN: list = []


@pytest.fixture
def eig_spy(monkeypatch):
    """numpy.linalg.eig recording the BLAS thread counts at each call."""
    seen = []
    eig = np.linalg.eig

    def spy(a):
        seen.append(_blas_counts())
        return eig(a)

    monkeypatch.setattr(np.linalg, "eig", spy)
    return seen


def test_the_scope_sets_one_thread_and_puts_the_callers_back():
    with threadpool_limits(limits=CALLER, user_api="blas"):
        assert set(_blas_counts()) == {CALLER}
        with threads.blas_limit():
            assert set(_blas_counts()) == {threads.THREADS}
            with threads.blas_limit():  # nested: still one thread, nothing put back early
                pass
            assert set(_blas_counts()) == {threads.THREADS}
        assert set(_blas_counts()) == {CALLER}
        with pytest.raises(ZeroDivisionError):
            threads.blas_limited(lambda: 1 / 0)()
        assert set(_blas_counts()) == {CALLER}  # put back when the call raises too


def test_the_library_finds_every_blas_threadpoolctl_sees():
    """numpy's and scipy's OpenBLAS (two builds in their wheels): the limit misses none."""
    assert len(threads.blas_libraries()) == len(_blas_counts()) >= 1


def test_a_beam_run_through_the_api_runs_single_threaded(eig_spy):
    import treeimpact as ti

    with threadpool_limits(limits=CALLER, user_api="blas"):
        run = ti.simulate(_fresh_scenario(), backend="beam")
        after = _blas_counts()
    assert eig_spy, "the beam run did not reach numpy.linalg.eig (the spy saw nothing)"
    assert all(set(c) == {threads.THREADS} for c in eig_spy)
    assert set(after) == {CALLER}
    assert np.isfinite(run.metrics.x_max)


_CLI_CHILD = """
import json, sys
import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits
from treeimpact.compare.interface.cli import main

def counts():
    return sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")

seen, eig = [], np.linalg.eig
def spy(a):
    seen.append(counts())
    return eig(a)
np.linalg.eig = spy
with threadpool_limits(limits=2, user_api="blas"):
    code = main(sys.argv[1:])
    after = counts()
print(json.dumps({"code": code, "seen": seen, "after": after}))
"""


def test_a_cli_command_without_the_variable_runs_single_threaded(tmp_path):
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", _CLI_CHILD, "simulate", "central-leader",
                          "--backend", "beam", "--json"], capture_output=True, text=True,
                         env=env, cwd=tmp_path, timeout=300)
    assert out.returncode == 0, out.stderr
    report = json.loads(out.stdout.strip().splitlines()[-1])
    assert report["code"] == 0
    assert report["seen"] and all(set(c) == {threads.THREADS} for c in report["seen"])
    assert set(report["after"]) == {2}


_POOL_CHILD = """
import json
from threadpoolctl import threadpool_limits
from treeimpact.compare.runs.pool import process_map
import pooled

with threadpool_limits(limits=2, user_api="blas"):
    print(json.dumps(process_map(pooled.counts, [0, 1], workers=2)))
"""
_POOLED = """
from threadpoolctl import threadpool_info

def counts(_item):
    return sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")
"""


def test_a_local_pool_worker_without_the_variable_runs_single_threaded(tmp_path):
    """process_map's forkserver workers, started by a process without
    OPENBLAS_NUM_THREADS (the pooled function from a module of its own, which the workers
    import)."""
    (tmp_path / "pooled.py").write_text(_POOLED, encoding="utf-8")
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, (str(tmp_path), env.get("PYTHONPATH"))))
    out = subprocess.run([sys.executable, "-c", _POOL_CHILD], capture_output=True, text=True,
                         env=env, cwd=tmp_path, timeout=300)
    assert out.returncode == 0, out.stderr
    counts = json.loads(out.stdout.strip().splitlines()[-1])
    assert len(counts) == 2 and all(set(c) == {threads.THREADS} for c in counts)


def test_a_dask_worker_runs_single_threaded_and_keeps_its_setting():
    """An in-process Dask worker (threads of this process): one thread inside each chunk,
    the worker's own setting back after it."""
    from distributed import Client, LocalCluster

    from treeimpact.compare.runs.pool import run_chunks

    got = []
    with threadpool_limits(limits=CALLER, user_api="blas"), \
            LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                         dashboard_address=None) as cluster, Client(cluster) as client:
        run_chunks(_chunk_threads, [[0], [1]], workers=1, client=client,
                   on_result=lambda chunk, outcomes: got.extend(outcomes), on_died=None)
        after = _blas_counts()
    assert len(got) == 2 and all(set(c) == {threads.THREADS} for c in got)
    assert set(after) == {CALLER}


def _chunk_threads(chunk: list) -> list:
    return [_blas_counts() for _ in chunk]
