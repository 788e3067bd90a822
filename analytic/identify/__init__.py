"""Tree properties from a pendulum-test record: the paper's procedure (eqs 39-48) and the
whole-record fit."""
