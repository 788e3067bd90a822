"""Floor 5 of compare, the interface (docs/architecture.md): the public API's functions and
typed results, the command line (one module per command, the parser in :mod:`.cli`) and the
process policy (signals, how a command ends)."""
