"""The results server: a REST API over the results database (``create_app``).

Errors of its own (:mod:`api.errors` maps them, and those of :mod:`db`, to answers)::

    station.domain.errors.CalstationError
    ├── CalibrationMismatchError   verification.py  the poses do not give the submitted
    │                                               coefficients (422)
    ├── ReportsBusyError           report_pool.py   every report process stayed busy (503)
    └── ReadTimeoutError           report_pool.py   a read outran the read timeout (503)
"""
