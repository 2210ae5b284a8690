"""Noise to analyse: power-law generators and built-in reference data.

Holds the generators of the design tip and of Kasdin–Walter (``generate``),
their expected variances (``expected``) and
the NBS reference data sets (``datasets``). May import: :mod:`sigmatau.core`
and :mod:`sigmatau.errors`.
"""
