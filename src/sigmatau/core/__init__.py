"""Foundation: what every layer above builds on, importing only numpy and :mod:`sigmatau.errors`.

Holds input validation and phase/frequency conversion (``validate``), τ grids
and the per-statistic limits (``taus``), numeric building blocks (``numeric``),
the Allan-family kernels shared with noise identification (``kernels``), their
fused compiled twins (``fused``, loops in ``compiled``; numba, imported only when
``accel`` chooses them), the
expected variance of each power-law noise (``powerlaw``), the result type
(``result``) and the raw computation of one statistic together with the
:class:`~sigmatau.core.driver.StreamedSeries` protocol through which records
computed piecewise reach it (``driver``), and the scope in which the statistics
of one record share its validated samples, phase and noise identification
(``shared``). May import: nothing of sigmatau but
:mod:`sigmatau.errors` (and numba, optionally, in ``fused`` and ``compiled``).
"""
