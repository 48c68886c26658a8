"""The end-of-line report: yields, failure Pareto, process capability, control charts.

The numbers are computed by SQL in :mod:`db.reports` into a
:class:`station.report.model.EolReport`; this package holds the report's shape
(``model``), its parameters and limits (``bounds``), the capability math
(``capability``) and the renderers (``render``: text, CSV, JSON, HTML; ``svg``: the
charts), so every format shows the same numbers.
"""
