"""Public shapes of the API's answers (the run record itself is
:mod:`station.domain.record.records`)."""

from datetime import datetime
from typing import Annotated
from uuid import UUID

from pydantic import AfterValidator, BaseModel, Field

from station.domain.constants import ReviewDecision
from station.domain.gyro.fit import GyroFitReport
from station.domain.gyro.log import GyroDwells
from station.domain.record.records import (
    Disposition,
    GyroFitRecord,
    GyroSummary,
    HoldReview,
    LogSource,
    Reason,
    RunSummary,
    Verdict,
)
from station.domain.sensors.record_bounds import plain_document


class Problem(BaseModel):
    """Body of every 4xx/5xx answer but 422: one line saying what is wrong."""

    detail: str


class FieldError(BaseModel):
    """One offending field of a refused request."""

    loc: Annotated[str, Field(description="where: body.poses.0.std, query.from, …")]
    msg: str
    type: str


class ValidationProblem(BaseModel):
    """Body of every 422 answer: one line naming the first fields, then each of them."""

    detail: str
    errors: list[FieldError]


class Health(BaseModel):
    """``GET /healthz``."""

    status: str
    database: str


class RunList(BaseModel):
    """A list of runs; ``next_cursor`` fetches the next page (``null`` on the last)."""

    data: list[RunSummary]
    count: int
    next_cursor: str | None = None


class RunEvent(BaseModel):
    """A stored run, as ``GET /api/v1/events`` pushes it (the ``data`` of a ``run`` event)."""

    run_id: UUID
    serial: str
    station_id: str
    operator_id: str
    lot: str | None
    started_at: datetime
    finished_at: datetime
    verdict: Verdict
    disposition: Annotated[
        Disposition | None, Field(description="where the station sent the unit (None: not said)")
    ]
    failure: Annotated[str | None, Field(description="the code of its first failure reason")]
    unit: Annotated[str, Field(description="the unit's page: every run, links to each record")]


class GyroFitSubmission(BaseModel):
    """``POST /api/v1/units/{serial}/gyro``: a fit made in the lab, and the log it came from."""

    source: Annotated[LogSource, Field(description="the log it was fitted to")]
    report: Annotated[GyroFitReport, AfterValidator(plain_document)]
    dwells: Annotated[
        Annotated[GyroDwells, AfterValidator(plain_document)] | None,
        Field(description="the log's dwells, for the plot"),
    ] = None


class UnitGyro(BaseModel):
    """``GET /api/v1/units/{serial}/gyro``: the unit's gyro calibration.

    ``fit`` is the latest rate-table / centrifuge fit (bias, scale-factor matrix, bias-form
    and scale-factor-form g-sensitivity), to compensate the unit's gyros with; ``still``
    the gyros over the latest run's still poses.
    """

    serial: str
    fit: GyroFitRecord | None
    still: GyroSummary | None


class ReviewSubmission(BaseModel):
    """``POST /api/v1/units/{serial}/reviews``: a quality review of the unit's latest,
    failed run (:class:`station.domain.record.records.HoldReview`; the reviewer is the key's
    holder, the time the server's)."""

    model_config = {"extra": "forbid"}

    run_id: Annotated[UUID, Field(description="the unit's latest run, the one on hold")]
    root_cause: Reason
    repair_action: Reason
    decision: Annotated[
        ReviewDecision,
        Field(description="retest: calibrate it again (attempts count afresh); scrap"),
    ]


class ReviewForm(ReviewSubmission):
    """The review form of a unit's page (``POST /units/{serial}/reviews``): the review,
    and the quality key typed into the form (checked as the API checks its bearer key)."""

    key: Annotated[
        str, Field(max_length=200, description="a quality engineer's API key, as typed")
    ] = ""


class ReviewList(BaseModel):
    """``GET /api/v1/units/{serial}/reviews``: the unit's reviews, oldest first."""

    data: list[HoldReview]
    count: int
