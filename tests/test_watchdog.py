"""The test run cannot hang: the root conftest's watchdog (conftest.TEST_LIMIT_S) ends a
pytest process whose exit is blocked, with every thread's stack."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_a_thread_that_outlives_its_test_ends_the_run_at_the_limit_with_its_stack(tmp_path):
    """A test leaves a 60 s non-daemon thread (the interpreter's exit waits for it, as a
    reader thread of an unkilled child did in CI); with a 3 s limit the run ends with an
    error and the stacks within seconds, not after 60 s."""
    (tmp_path / "test_leaves_a_thread.py").write_text(
        "import threading, time\n\n"
        "def test_leaves_a_thread():\n"
        "    threading.Thread(target=time.sleep, args=(60,)).start()\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT), TREEIMPACT_TEST_LIMIT_S="3")
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "conftest",
         "test_leaves_a_thread.py"], cwd=tmp_path, env=env, capture_output=True, text=True,
        timeout=40)  # 40 s: far below the thread's 60 s, far above the 3 s limit
    assert "1 passed" in proc.stdout
    assert proc.returncode != 0
    assert "Timeout (0:00:03)!" in proc.stderr and "in _shutdown" in proc.stderr
