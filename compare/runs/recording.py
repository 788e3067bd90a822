"""A run as a field test would record it: the trunk's displacement at the clamp sampled at a
rate, from a rest before the impact, with the sensor's Gaussian noise (``treeimpact
simulate --record`` and :func:`treeimpact.record_from_simulation`). SI units."""

from __future__ import annotations

import numpy as np

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.parameters import check_range

#: Allowed sampling rates (Hz) and noise (a fraction of the peak), and the rest (s) a
#: record keeps before the impact.
RATE_RANGE, NOISE_RANGE, REST = (50.0, 1e6), (0.0, 0.5), 0.02
#: A recorder's defaults: 5 kHz, no noise, seed 0.
DEFAULTS = {"rate": 5000.0, "noise": 0.0, "seed": 0}


def check_sampling(rate, noise, seed, names=("--rate", "--noise", "--seed")) -> None:
    """``rate`` (Hz), ``noise`` (of the peak) and ``seed`` in range, else a one-line
    ParameterError naming them as ``names`` (flags, or the API's keywords)."""
    check_range(names[0], rate, low=RATE_RANGE[0], high=RATE_RANGE[1], unit="Hz")
    check_range(names[1], noise, low=NOISE_RANGE[0], high=NOISE_RANGE[1])
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ParameterError(f"{names[2]} = {seed!r}: allowed integers 0 or more")


def sample(result, rate: float, noise: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(t, x): ``result``'s trunk displacement x (m) at ``rate`` Hz from :data:`REST` s before
    the impact (t = 0 at the first sample, the impact at t = REST), with ``noise`` x its peak
    as Gaussian noise from ``seed``: exact samples of the analytic backend's solution, else
    the backend's trajectory interpolated. Raises ParameterError for a result without a
    trajectory."""
    traj = result.trajectory
    if traj is None:
        raise ParameterError(f"record: the {result.backend} backend gives no trajectory")
    s = np.arange(-REST, float(traj.t[-1]), 1.0 / rate)
    sol = getattr(result, "solution", None)
    if sol is not None:
        x = np.where(s > 0.0, sol.state(np.clip(s, 0.0, sol.t_end))[0], 0.0)
    else:
        x = np.where(s > 0.0, np.interp(s, traj.t, traj.x), 0.0)
    rng = np.random.default_rng(seed)
    x = x + noise * float(np.max(np.abs(x))) * rng.standard_normal(s.size)
    return s + REST, x
