"""What a station's outbox holds, as the station reports it with each run it sends.

The station sends the report in a request header of ``POST /api/v1/runs`` (the run
record stays as it is; a station that sends none is stored as before)::

    Calstation-Outbox: queued=12; oldest_s=5400; set_aside=1

- ``queued``: runs waiting in the outbox behind the one being sent;
- ``oldest_s``: whole seconds the oldest of those has waited (0 when none waits), an
  age rather than a time, so that the station's clock and the server's need not agree;
- ``set_aside``: files the outbox set aside (refused by the store, or unreadable).

The server keeps each station's latest report (the ``[[outbox]]`` alert rule,
:mod:`station.domain.quality.alerts`, reads it).
"""

import re
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from station.domain.errors import InputError, validation_problem

#: The request header that carries the report.
OUTBOX_HEADER = "Calstation-Outbox"
#: The most a figure of the report may be (a 32-bit column holds it).
_MOST = 2**31 - 1
#: One ``name=figure`` of the header.
_FIGURE = re.compile(r"\s*([a-z_]+)\s*=\s*([0-9]{1,12})\s*")


class OutboxReport(BaseModel):
    """A station's outbox when it sent a run: runs queued behind it, the oldest one's
    wait, files set aside."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    queued: Annotated[int, Field(ge=0, le=_MOST, description="runs queued behind this one")]
    oldest_s: Annotated[
        int, Field(ge=0, le=_MOST, description="seconds the oldest queued run has waited")
    ]
    set_aside: Annotated[
        int, Field(ge=0, le=_MOST, description="outbox files set aside (refused, unreadable)")
    ]

    def header(self) -> str:
        """The report as the header's value."""
        return f"queued={self.queued}; oldest_s={self.oldest_s}; set_aside={self.set_aside}"


def parse_outbox_header(value: str) -> OutboxReport:
    """The report in a header ``value``, or an :class:`InputError` naming what is wrong
    (every figure once, whole numbers from 0)."""
    figures: dict[str, int] = {}
    for part in value.split(";"):
        found = _FIGURE.fullmatch(part)
        if found is None:
            raise InputError(f"{OUTBOX_HEADER}: {part.strip()!r} is not name=whole number")
        name, figure = found.groups()
        if name in figures:
            raise InputError(f"{OUTBOX_HEADER}: {name} given twice")
        figures[name] = int(figure)
    try:
        return OutboxReport.model_validate(figures)
    except ValidationError as exc:
        raise InputError(f"{OUTBOX_HEADER}: {validation_problem(exc)}") from None
