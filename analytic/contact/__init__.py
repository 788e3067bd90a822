"""The contact pad (k_c, c_c): its law, the soft-contact rung, the matched-loss model and
the engines' time-step rule."""
