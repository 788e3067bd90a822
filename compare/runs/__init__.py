"""Floor 1 of compare, what a run is (docs/architecture.md): the backends by name and the
engine registry, one run record and the session's run cache, the tolerance file, the
findings and the verdict of a comparison, the per-tree bounds, the rung table, the one pool,
the exit codes, progress, provenance and figure titles that fit."""
