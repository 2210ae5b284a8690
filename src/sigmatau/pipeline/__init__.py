"""The main job on a sensor log: what ``sigmatau analyze`` runs.

Holds :func:`~sigmatau.pipeline.analysis.analyze_log`: statistics, noise types
and intervals per channel, the IMU model, datasheet comparison and the Kalibr
entry, as a ``LogAnalysis`` (``analysis``). May import: :mod:`sigmatau.imu`,
:mod:`sigmatau.io` and every layer below them; never reports, the scale-out
layer or the CLI.
"""
