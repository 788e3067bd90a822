"""Progress of long runs on stderr: a tqdm bar on a terminal, else one line every few
seconds (logs and CI see how far a run is) and the honest wall time at the end; a run
shorter than a few seconds prints nothing."""

from __future__ import annotations

import sys
import time
import weakref

#: Seconds between two progress lines when stderr is not a terminal.
LINE_EVERY_S = 5.0
#: The bars drawn and not yet closed (:func:`end_open_bars`).
_OPEN_BARS: weakref.WeakSet = weakref.WeakSet()


def end_open_bars() -> None:
    """End every progress bar still drawn, its line closed by a newline where it stands, so
    that a message printed next (an error, "interrupted") starts a line of its own."""
    for progress in list(_OPEN_BARS):
        progress.abandon()


class Progress:
    """Counts finished items of ``total``; ``update(n)`` after each, ``close()`` at the end.
    ``desc``: the run's name on its lines; ``unit``: what an item is ("run", "step");
    ``stream``: where it writes (default stderr); ``bar``: a tqdm bar (None: on a terminal
    only), else a line every :data:`LINE_EVERY_S` seconds."""

    def __init__(self, total: int, desc: str, unit: str = "run", stream=None,
                 bar: bool | None = None):
        self.total, self.desc, self.unit = total, desc, unit
        self.stream = stream if stream is not None else sys.stderr
        self.done = 0
        self.start = self._last = time.perf_counter()
        self._lines = 0  # progress lines printed: a run shorter than LINE_EVERY_S prints none
        self._bar = None
        if bar or (bar is None and getattr(self.stream, "isatty", lambda: False)()):
            from tqdm import tqdm

            self._bar = tqdm(total=total, unit=unit, desc=desc, file=self.stream)
            _OPEN_BARS.add(self)

    def update(self, n: int = 1) -> None:
        """``n`` more items finished."""
        self.done += n
        if self._bar is not None:
            self._bar.update(n)
            return
        now = time.perf_counter()
        if now - self._last >= LINE_EVERY_S and self.done < self.total:  # close() says done
            self._last = now
            self._line(now)

    def _line(self, now: float, final: bool = False) -> None:
        if final and not self._lines and now - self.start < LINE_EVERY_S:
            return  # a short run needs no word on its progress
        self._lines += 1
        pct = 100.0 * self.done / self.total if self.total else 100.0
        word = "done" if final else "running"
        print(f"{self.desc}: {self.done}/{self.total} {self.unit}s ({pct:.0f} %), "
              f"{now - self.start:.1f} s, {word}", file=self.stream, flush=True)

    def close(self) -> None:
        """The end: the bar closed, or the final line (when the run lasted long enough to
        print any)."""
        if self._bar is not None:
            self.abandon()
        self._line(time.perf_counter(), final=True)

    def abandon(self) -> None:
        """The bar (if any) closed where it stands, its line ended by a newline; no final
        line. A run that fails or is stopped."""
        if self._bar is not None:
            _OPEN_BARS.discard(self)
            self._bar.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
