"""treeimpact.compare: the cross-checks, the discrepancy ladder, sweeps, the report and the
command line (the top layer: it imports analytic and the engine packages, never the reverse)."""
