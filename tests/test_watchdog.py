"""The test run cannot hang: the root conftest's watchdog (conftest.TEST_LIMIT_S) ends a
pytest process whose exit is blocked, with every thread's stack."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_a_thread_that_outlives_its_test_ends_the_run_at_the_limit_with_its_stack(tmp_path):
    """A test leaves a 90 s non-daemon thread (the interpreter's exit waits for it, as a
    reader thread of an unkilled child did in CI); with a 10 s limit the run ends with an
    error and the stacks within seconds of the limit, not after 90 s. The limit counts from
    pytest's start: 10 s, not 3 s, so that a loaded machine's start-up and collection (a 3 s
    limit fired before the test had passed once, at a load of 6 on 2 cores) stay inside it."""
    (tmp_path / "test_leaves_a_thread.py").write_text(
        "import threading, time\n\n"
        "def test_leaves_a_thread():\n"
        "    threading.Thread(target=time.sleep, args=(90,)).start()\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT), TREEIMPACT_TEST_LIMIT_S="10")
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "conftest",
         "test_leaves_a_thread.py"], cwd=tmp_path, env=env, capture_output=True, text=True,
        timeout=60)  # 60 s: far below the thread's 90 s, far above the 10 s limit
    assert "1 passed" in proc.stdout
    assert proc.returncode != 0
    assert "Timeout (0:00:10)!" in proc.stderr and "in _shutdown" in proc.stderr
