"""Which OpenBLAS kernels `make test` runs the ``numerics`` tests under, besides the
machine's own: ``python tests/blas_kernels.py`` prints two ``OPENBLAS_CORETYPE`` values
(space-separated) that this CPU can run and that differ from the kernel OpenBLAS picks for it,
or nothing where numpy's BLAS is not a dynamic-architecture OpenBLAS on x86-64 (the variable
would then change nothing). ``--own`` prints the kernel OpenBLAS picked (a forced
``OPENBLAS_CORETYPE`` included). Not a test module: pytest collects ``test_*.py`` only.

numpy picks its kernels by CPU: a result that moves with them moves between users'
machines, so the tests whose numbers depend on BLAS round-off (conftest.py's NUMERICS) run
under other machines' kernels too (docs/reproducibility.md).
"""

from __future__ import annotations

import ctypes
import glob
import os
import platform
import sys

#: Candidates in the order tried: (OPENBLAS_CORETYPE, the /proc/cpuinfo flags it needs).
#: Prescott is the SSE3 baseline every x86-64 CPU runs; Haswell AVX2 and FMA (Zen's
#: kernels are Haswell's); Sandybridge AVX; SkylakeX AVX-512.
CANDIDATES = (("Prescott", ()), ("Haswell", ("avx2", "fma")), ("Sandybridge", ("avx",)),
              ("SkylakeX", ("avx512f", "avx512bw", "avx512vl")))
#: What OpenBLAS names the kernel it runs for each candidate (Prescott runs as Katmai).
RUNS_AS = {"Prescott": "Katmai"}


def own_kernel() -> str | None:
    """The kernel numpy's OpenBLAS runs here (None: not an OpenBLAS that says so)."""
    import numpy

    root = os.path.dirname(numpy.__file__)
    for lib in glob.glob(os.path.join(root, "..", "numpy.libs", "*openblas*")) + glob.glob(
            os.path.join(root, ".dylibs", "*openblas*")):
        handle = ctypes.CDLL(lib)
        for symbol in ("scipy_openblas_get_corename64_", "openblas_get_corename64_",
                       "openblas_get_corename"):
            if hasattr(handle, symbol):
                func = getattr(handle, symbol)
                func.restype = ctypes.c_char_p
                return func().decode()
    return None


def cpu_flags() -> set[str]:
    try:
        with open("/proc/cpuinfo") as f:
            line = next(s for s in f if s.startswith("flags"))
    except (OSError, StopIteration):
        return set()
    return set(line.split(":", 1)[1].split())


def other_kernels(own: str | None, flags: set[str], count: int = 2) -> list[str]:
    """Up to ``count`` candidates this CPU supports whose kernel is not ``own``."""
    if own is None or platform.machine().lower() not in ("x86_64", "amd64"):
        return []
    out = []
    for name, needs in CANDIDATES:
        if RUNS_AS.get(name, name).lower() != own.lower() and all(f in flags for f in needs):
            out.append(name)
    return out[:count]


def main(argv: list[str]) -> int:
    if argv[1:] == ["--own"]:
        print(own_kernel() or "unknown")
        return 0
    env = dict(os.environ)
    env.pop("OPENBLAS_CORETYPE", None)
    if "OPENBLAS_CORETYPE" in os.environ:  # the machine's own, not a forced one
        import subprocess

        own = subprocess.run([sys.executable, __file__, "--own"], env=env,
                             capture_output=True, text=True).stdout.strip()
        own = None if own == "unknown" else own
    else:
        own = own_kernel()
    print(" ".join(other_kernels(own, cpu_flags())))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
