"""Scale-out: several channels, records larger than memory, fleets of logs.

Holds one statistic over several channels in threads (``channels``), the
statistics streamed piecewise over ``.npy``/binary/HDF5 files and dask arrays
(``chunked``: it implements the core's
:class:`~sigmatau.core.driver.StreamedSeries` protocol and registers dask arrays
as such records) and many logs on a Dask cluster (``batch``). May import:
:mod:`sigmatau.report`, :mod:`sigmatau.pipeline` and every layer below; dask
and distributed only when used.
"""
