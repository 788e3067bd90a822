"""The local process pool every part of ``compare`` uses for independent runs (the report,
``pytest compare``, the identification and contact studies); sweeps add journaling, broken
worker recovery and Dask on top (compare.sweep.run)."""

from __future__ import annotations

import os


def process_map(fn, items, *, workers: int | None = None, done=None) -> list:
    """``[fn(item) for item in items]`` in worker processes, in the items' order.

    ``fn`` must pickle (a module-level function). ``workers``: default the CPU count; 1, or
    a single item, runs in this process. Workers start by ``forkserver`` (the engines' thread
    pools are never forked). ``done()`` is called once per finished item (progress).
    """
    items = list(items)
    if workers is None:
        workers = os.cpu_count() or 1
    if workers <= 1 or len(items) <= 1:
        out = []
        for item in items:
            out.append(fn(item))
            if done is not None:
                done()
        return out
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    ctx = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(max_workers=min(workers, len(items)), mp_context=ctx) as pool:
        futures = [pool.submit(fn, item) for item in items]
        out = []
        for fut in futures:
            out.append(fut.result())
            if done is not None:
                done()
    return out
