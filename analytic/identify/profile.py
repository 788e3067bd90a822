"""The global stage of the record fit: e's profile, the cost with e held on a grid and the
other parameters fitted (e has a local minimum per number of impacts before the bodies move
together or part), and the one-impact ridge it reveals. docs/identification.md, "What a
record fixes"."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .fit_parameters import E_MAX, Slot
from .fitter import Fit, Fitter
from .one_impact import one_impact
from .procedure import PendulumTest

#: The profile's grid of e: finer below 0.2, where a pad's e usually is and a chattering
#: branch per impact lies. Its lowest point starts the fit with e free, and the points
#: within the 95 % likelihood-ratio threshold widen the intervals (a profile likelihood).
PROFILE_RESTITUTIONS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
PROFILE_SAMPLES = 2000  # the profile fits every k-th sample, at most this many
#: (e, the trunk's damping ratio) fitted from a first guess too (the first at e = 0 is the
#: robust fit's): each
#: branch, and a lightly damped start (a short record has a basin per damping too)
PROFILE_FRESH = ((0.0, 0.1), (0.3, 0.1), (0.3, 0.02), (0.6, 0.1), (0.9, 0.1))
PROFILE_NFEV_FIRST = 20  # evaluations of the robust fit from the first guess at e = 0
PROFILE_NFEV_FRESH = 15  # ... of a fit from a first guess
PROFILE_NFEV = 6  # ... from a neighbour's optimum: a few steps
PROFILE_ZOOM = 3  # halvings of the grid's spacing around its lowest local minima ...
PROFILE_BASINS = 2  # ... this many of them
Z95 = 1.959963984540054  # two-sided 95 % normal quantile
CHI2_95 = Z95 * Z95  # 3.84: the likelihood-ratio threshold of one parameter at 95 %


class RestitutionProfile:
    """The fit's cost with e held at each of :data:`PROFILE_RESTITUTIONS` (the others
    fitted) on every k-th kept sample (at most :data:`PROFILE_SAMPLES`). Fresh fits from a
    first guess at each of :data:`PROFILE_FRESH` (the branches: chattering into moving
    together, or the pendulum leaving); a sweep up the grid, each point from its
    neighbour's optimum or the fresh fit there, whichever is better; a sweep down, each
    point kept if it improves; then around its two lowest local minima at half, a quarter
    and an eighth of the grid's spacing (e's cost has a kink wherever an impact appears,
    and narrow dips between). Its lowest point starts the fit with e free; the points within
    the likelihood-ratio threshold of the optimum are the restitutions the record cannot
    rule out (a profile likelihood). ``fitter``: the record's; ``keep``: the samples fitted
    (a boolean mask); ``guess(e, trunk_damping_ratio)``: a first guess on e's branch;
    ``first``: the robust stage's fit, one more start."""

    def __init__(self, fitter: Fitter, guess, keep, first: Fit):
        self.fitter, self.keep = fitter, keep
        self.stride = max(1, int(math.ceil(np.count_nonzero(keep) / PROFILE_SAMPLES)))
        self.params = fitter.params.freeze(Slot.RESTITUTION)
        self.points = self._grid(self._fresh(guess, first))
        self._zoom(self._centres())
        self.points.sort(key=lambda f: f.p[Slot.RESTITUTION])
        self.best = min(self.points, key=lambda f: f.cost)
        self._floor = None

    def _fresh(self, guess, first: Fit) -> dict:
        """e -> the best fit from a first guess there (at e = 0 from the robust fit)."""
        fresh = {PROFILE_RESTITUTIONS[0]: self._at(first.p, PROFILE_RESTITUTIONS[0])}
        for e, ratio in PROFILE_FRESH[1:]:
            f = self.fitter.fit(guess(e, ratio), keep=self.keep, stride=self.stride,
                                params=self.params, max_nfev=PROFILE_NFEV_FRESH)
            if e not in fresh or f.cost < fresh[e].cost:
                fresh[e] = f
        return fresh

    def _grid(self, fresh: dict) -> list:
        """The grid swept up from the fresh fits and neighbours, then down."""
        grid = PROFILE_RESTITUTIONS
        points = []
        for e in grid:
            f = self._at(points[-1].p, e) if points else fresh[e]
            if e in fresh and fresh[e].cost < f.cost:
                f = fresh[e]
            points.append(f)
        for i in range(len(grid) - 2, -1, -1):
            f = self._at(points[i + 1].p, grid[i])
            if f.cost < points[i].cost:
                points[i] = f
        return points

    def _centres(self) -> list:
        """The lowest local minima of the grid (a point no higher than its neighbours), one
        per valley (a flat stretch between two, the one-impact ridge, is one valley)."""
        points, n = self.points, len(self.points)
        minima = sorted((i for i in range(n) if all(
            points[j].cost >= points[i].cost for j in (i - 1, i + 1) if 0 <= j < n)),
            key=lambda i: points[i].cost)

        def same_valley(i, j):
            top = max(points[i].cost, points[j].cost) * (1.0 + 1e-4)
            return all(points[k].cost <= top for k in range(min(i, j), max(i, j) + 1))

        chosen = []
        for i in minima:
            if not any(same_valley(i, j) for j in chosen):
                chosen.append(i)
        return [points[i] for i in chosen[:PROFILE_BASINS]]

    def _zoom(self, centres: list) -> None:
        """Halve the spacing around each centre PROFILE_ZOOM times, moving to the lower."""
        h = 0.1
        for _ in range(PROFILE_ZOOM):
            h *= 0.5
            for k, c in enumerate(centres):
                have = {round(float(f.p[Slot.RESTITUTION]), 9) for f in self.points}
                e0 = c.p[Slot.RESTITUTION]
                new = [self._at(c.p, e) for e in (e0 - h, e0 + h)
                       if 0.0 <= e <= E_MAX and round(e, 9) not in have]
                self.points.extend(new)
                centres[k] = min([c, *new], key=lambda f: f.cost)
        self.centres = sorted(centres, key=lambda f: f.cost)

    def starts(self) -> list:
        """Where the fit with e free starts: the lowest point, and the other basin's lowest
        when it is as low within the 95 % threshold (its noise from the cost itself)."""
        n = self.best.problem.data.size
        threshold = 0.5 * CHI2_95 * 2.0 * self.best.cost / max(n, 1)
        return [c.p for c in self.centres if c.cost <= self.best.cost + threshold] or [
            self.best.p]

    def _at(self, p, e: float) -> Fit:
        p0 = np.array(p, float)
        p0[Slot.RESTITUTION] = e
        return self.fitter.fit(p0, keep=self.keep, stride=self.stride, params=self.params,
                               max_nfev=PROFILE_NFEV)

    def _min(self, best: Fit) -> float:
        """The lowest cost on the profile's samples: its points' and the free fit's."""
        if self._floor is None:
            prob = self.points[0].problem
            r = prob.residual(best.p[list(prob.free)])
            self._floor = min(0.5 * float(r @ r), min(f.cost for f in self.points))
        return self._floor

    def basins(self, best: Fit, threshold: float) -> list:
        """The lowest points (p) of the profile's valleys (up to PROFILE_BASINS) whose cost is
        within ``threshold`` of the lowest (the profile's or the ``best`` fit's): each another
        explanation of the record (a second basin in e and M_T) the intervals must cover."""
        level = self._min(best) + threshold
        return [c.p for c in self.centres if c.cost <= level]

    def inside(self, best: Fit, threshold: float) -> list:
        """The points (p) of the restitutions the record cannot rule out: the profile's
        within ``threshold`` of the lower of its own and the ``best`` fit's cost and, at each
        end of that range, the point where the cost crosses it (the neighbours' optima
        interpolated linearly)."""
        level = self._min(best) + threshold
        out = [f.p for f in self.points if f.cost <= level]
        return out + [q for q, _ in self._ends(level) if q is not None]

    def reaches_top(self, best: Fit, threshold: float) -> bool:
        """Whether the profile's top point (e at the grid's top) is within ``threshold`` of
        the lower of its own and the ``best`` fit's cost."""
        top = self.points[-1]
        return (top.p[Slot.RESTITUTION] >= PROFILE_RESTITUTIONS[-1]
                and top.cost <= self._min(best) + threshold)

    def e_range(self, best: Fit, threshold: float) -> tuple[float, float]:
        """(low, high): the restitutions within ``threshold`` (the profile's and the free
        fit's own, ``best``), to the first point outside it on each side (the crossing lies
        between:
        a range as wide as the profile's spacing there can tell, not narrower; 0 and 1 past
        the ends of the profile)."""
        level = self._min(best) + threshold
        es = [float(f.p[Slot.RESTITUTION]) for f in self.points] + [
            float(best.p[Slot.RESTITUTION])]
        ok = [f.cost <= level for f in self.points] + [True]
        order = np.argsort(es, kind="stable")
        es, ok = [es[i] for i in order], [ok[i] for i in order]
        i = ok.index(True)
        j = len(ok) - 1 - ok[::-1].index(True)
        return (0.0 if i == 0 else es[i - 1], 1.0 if j == len(es) - 1 else es[j + 1])

    def _ends(self, level: float) -> list:
        """[(p or None, e)] at the low and the high end of the range within ``level``: the
        crossing of the cost, the neighbours' optima interpolated linearly in it."""
        cost = [f.cost for f in self.points]
        ins = [i for i, c in enumerate(cost) if c <= level]
        if not ins:
            return [(None, math.nan), (None, math.nan)]

        def cross(a, b):  # a inside, b outside
            frac = min(max((level - cost[a]) / max(cost[b] - cost[a], 1e-300), 0.0), 1.0)
            q = self.points[a].p + frac * (self.points[b].p - self.points[a].p)
            return q, float(q[Slot.RESTITUTION])

        i, j = ins[0], ins[-1]
        return [(None, 0.0) if i == 0 else cross(i, i - 1),
                (None, 1.0) if j == len(cost) - 1 else cross(j, j + 1)]


@dataclass
class Ridge:
    """A one-impact record's ridge: M_T and e not fixed apart."""

    one: np.ndarray  # a one-impact optimum (M_T and e free along the ridge)
    low: np.ndarray  # the lowest-e point explaining the record as well (on or off the ridge)
    e_low: float


def find_ridge(fitter: Fitter, profile: RestitutionProfile, best: Fit, keep,
               test: PendulumTest, threshold: float) -> Ridge | None:
    """The ridge when the ``profile``'s top point, within ``threshold`` of the ``best`` fit,
    is a one-impact model with the pendulum of ``test`` (the pendulum leaves and does not
    return within the samples ``keep`` selects of ``fitter``'s record): M_T and e not fixed
    apart; None when it is not (a flat profile of a record that still fixes M_T)."""
    one = profile.points[-1].p
    if not one_impact(one, test, float(fitter.t[keep][-1] - one[Slot.T0])):
        return None
    low = profile.inside(best, threshold)[0]
    return Ridge(one=one, low=low, e_low=profile.e_range(best, threshold)[0])
