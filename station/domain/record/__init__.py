"""The unit's record: what a calibration attempt leaves behind, and what it makes of a unit.

The run record and its parts (``records``), a unit's state read from its runs
(``unit_state``), a signatory's signature of a certificate (``signature``), and the
outbox report a station sends with a run (``outbox_report``). It holds the results of
the calibration and the gyros, never the product catalogue: what depends on a product
(its sensor's ADC range, its limits) is passed in by the caller that holds the product.
"""
