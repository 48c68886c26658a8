"""Public shapes of the API's answers (the run record itself is :mod:`station.records`)."""

from typing import Annotated

from pydantic import BaseModel, Field

from station.gyro.fit import GyroFitReport
from station.gyro.log import GyroDwells
from station.records import GyroFitRecord, GyroSummary, RunSummary


class Problem(BaseModel):
    """Body of every 4xx/5xx answer."""

    detail: str


class Health(BaseModel):
    """``GET /healthz``."""

    status: str
    database: str


class RunList(BaseModel):
    """A list of runs; ``next_cursor`` fetches the next page (``null`` on the last)."""

    data: list[RunSummary]
    count: int
    next_cursor: str | None = None


class GyroFitSubmission(BaseModel):
    """``POST /api/v1/units/{serial}/gyro``: a fit made in the lab, and the log it came from."""

    source: Annotated[
        str, Field(min_length=1, max_length=255, description="the log it was fitted to")
    ]
    report: GyroFitReport
    dwells: Annotated[GyroDwells | None, Field(description="the log's dwells, for the plot")] = None


class UnitGyro(BaseModel):
    """``GET /api/v1/units/{serial}/gyro``: the unit's gyro calibration.

    ``fit`` is the latest rate-table / centrifuge fit (bias, scale-factor matrix, bias-form
    and scale-factor-form g-sensitivity), to compensate the unit's gyros with; ``still``
    the gyros over the latest run's still poses.
    """

    serial: str
    fit: GyroFitRecord | None
    still: GyroSummary | None
