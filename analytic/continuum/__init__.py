"""The flexible trunk: Euler-Bernoulli beam, hinged chain, natural frequencies and the
continuum impact rung."""
