"""The end-of-line report, rendered: yields, failure Pareto, process capability, control charts.

The numbers are computed by SQL in :mod:`db.report.reports` into a
:class:`station.domain.quality.figures.EolReport` (the report's figures, parameters and
capability math are domain: :mod:`station.domain.quality`); this package renders them
(``render``: text, CSV, JSON, HTML; ``svg``: the charts; ``gyro_plot``: the gyro
g-sensitivity figure), so every format shows the same numbers, and reads the period a
report covers (``period``).
"""
