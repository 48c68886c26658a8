"""Who issues a calibration certificate, for whom, and to what its reference is traceable.

ISO/IEC 17025:2017 7.8.2.1 asks a report to name the laboratory and its address (b),
where the work was done when not at that address (c), and the customer (e); 7.8.4.1 c a
statement of metrological traceability (6.5). None of that is in a run's record: it is
the laboratory's configuration, a ``[laboratory]`` table in the station's configuration
file (``station.loop.config``) and in the results server's ``CALSTATION_LABORATORY_FILE``
(``api.settings``), read by :func:`load_laboratory`. A field not configured prints as
"not configured" on the certificate.

The reference of this calibration is the local acceleration of gravity: the six-position
method [Song2006] measures each axis against 1 g, so the certificate's traceability
statement names the value of g used and what that value is traceable to (a gravity survey,
a national metrology institute's absolute gravimeter).
"""

from pathlib import Path
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from station.domain.errors import InputError, validation_problem
from station.domain.toml_text import parse_toml, read_text

#: One line of a certificate's identity: printable, no line breaks.
_Line = Annotated[str, Field(min_length=1, max_length=300, pattern=r"^[^\x00-\x1f\x7f]+$")]


class Laboratory(BaseModel):
    """The laboratory's identity on its certificates (ISO/IEC 17025:2017 7.8.2.1 b, c, e;
    7.8.4.1 c). ``location``: where the calibrations are performed (the line, the
    station's room) when it is not ``address``; ``gravity_m_s2`` and ``traceability``:
    the local g the six-position method measures against and what it is traceable to."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: _Line | None = None
    address: _Line | None = None
    location: _Line | None = None
    customer: _Line | None = None
    gravity_m_s2: Annotated[float, Field(gt=9.7, lt=9.9)] | None = None
    traceability: _Line | None = None


def load_laboratory(path: Path) -> Laboratory:
    """The ``[laboratory]`` table of the TOML file ``path``: an :class:`InputError` of
    one line when it cannot be read, is not TOML or holds a field that is not one."""
    table = parse_toml(read_text(path, "laboratory"), str(path)).get("laboratory")
    if not isinstance(table, dict):
        raise InputError(f"{path}: no [laboratory] table")
    try:
        return Laboratory.model_validate(table)
    except ValidationError as exc:
        raise InputError(f"{path}: [laboratory]: {validation_problem(exc)}") from None
