"""What the end-of-line report says, apart from how it is computed or shown.

Domain, like :mod:`station.domain.record.records` and :mod:`station.domain.product.limits`: the
report's figures
(``figures``: :class:`~station.domain.quality.figures.EolReport` and its parts), the
parameters it measures and the limits it measures them against (``parameters``), and
the capability statistics (``capability``). :mod:`db.report.reports` fills the figures with SQL;
:mod:`station.report` renders them.
"""
