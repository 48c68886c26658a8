"""A small line history whose report numbers are worked out by hand in the tests.

Seven runs of five units at two stations by two operators inside the range, one run
outside it::

    t (min)  unit   station  operator  verdict  first failure       offset_x  offset_y
      0      U1     st1      op-a      pass                          2040      2048
     10      U2     st1      op-a      fail     sensitivity          2050      2048
     20      U3     st2      op-b      fail     offset               2060      2260 (out)
     30      U4     st2      op-b      pass                          2045      2048
     40      U5     st1      op-b      fail     offset               2055      2240 (marginal)
     50      U2     st1      op-a      pass                          2048      2048
     60      U3     st2      op-b      fail     verification_error   2052      2048
    300      U9     st1      op-a      pass     (after the range)    2100      2048
"""

from datetime import timedelta

from sqlalchemy.orm import Session

from db import RunRepository
from tests.db.records import T0, make_record

SINCE, UNTIL = T0, T0 + timedelta(hours=2)

#: (minute, serial, station, operator, first failure code or None, offset_x, offset_y)
RUNS = [
    (0, "U1", "st1", "op-a", None, 2040.0, 2048.0),
    (10, "U2", "st1", "op-a", "sensitivity", 2050.0, 2048.0),
    (20, "U3", "st2", "op-b", "offset", 2060.0, 2260.0),
    (30, "U4", "st2", "op-b", None, 2045.0, 2048.0),
    (40, "U5", "st1", "op-b", "offset", 2055.0, 2240.0),
    (50, "U2", "st1", "op-a", None, 2048.0, 2048.0),
    (60, "U3", "st2", "op-b", "verification_error", 2052.0, 2048.0),
    (300, "U9", "st1", "op-a", None, 2100.0, 2048.0),
]
IN_RANGE = RUNS[:-1]


def _failures(code: str | None) -> list[dict[str, object]]:
    if code is None:
        return []
    return [
        {"code": code, "message": f"{code} out of limits"},
        {"code": "link_loss", "message": "a second reason, never counted in the Pareto"},
    ]


def insert_line_history(session: Session) -> None:
    """Store :data:`RUNS` through the repository and commit."""
    repository = RunRepository(session)
    for minute, serial, station, operator, code, offset_x, offset_y in RUNS:
        repository.submit(
            make_record(
                serial=serial,
                station_id=station,
                operator_id=operator,
                verdict="fail" if code else "pass",
                started_at=T0 + timedelta(minutes=minute),
                offset=(offset_x, offset_y, 1960.5),
                failures=_failures(code),
            )
        )
    session.commit()
