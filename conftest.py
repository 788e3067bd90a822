"""Root pytest configuration shared by `tests` and `compare`.

OpenBLAS starts one thread per core for every small matrix operation; on the 2-core CI
machine those threads fight the test process itself and each call costs ~1 s. The suite
only handles matrices of a few hundred rows, so one BLAS thread is the fast choice.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
