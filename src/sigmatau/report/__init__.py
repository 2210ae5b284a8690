"""Presenting an analysis: output files, figures and the HTML report.

Holds the writer of results.json, CSV tables, imu.yaml, figures and report.html
into a directory replaced atomically (``outputs``), the matplotlib figures
(``plots``, matplotlib imported only when drawing) and the self-contained report
page (``html``). May import: :mod:`sigmatau.pipeline` and every layer below it.
"""
