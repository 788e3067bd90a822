"""Floor 2 of compare, one tree (docs/architecture.md): a scenario run as the ladder and
judged, the paper's procedure on a rung's record, the mechanism evidence, a user's tree's
scenario and the family of trees across the regimes."""
