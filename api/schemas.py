"""Public shapes of the API's answers (the run record itself is :mod:`station.records`)."""

from datetime import datetime
from typing import Annotated
from uuid import UUID

from pydantic import BaseModel, Field

from station.gyro.fit import GyroFitReport
from station.gyro.log import GyroDwells
from station.records import (
    FailureReason,
    GyroFitRecord,
    GyroSummary,
    LimitsRef,
    Matrix3,
    Model,
    QualityMetrics,
    RunSummary,
    Vector3,
    Verdict,
)


class Problem(BaseModel):
    """Body of every 4xx/5xx answer."""

    detail: str


class Health(BaseModel):
    """``GET /healthz``."""

    status: str
    database: str


class UnitCalibration(BaseModel):
    """A unit's current state: its latest run's verdict and calibration."""

    serial: str
    verdict: Verdict
    run_id: UUID
    calibrated_at: Annotated[datetime, Field(description="when the latest run finished (UTC)")]
    station_id: str
    operator_id: str
    software_version: str
    model: Model
    limits: LimitsRef
    offset: Annotated[Vector3 | None, Field(description="counts")]
    sensitivity: Annotated[Vector3 | None, Field(description="counts/g")]
    matrix: Annotated[Matrix3 | None, Field(description="counts → g, g = M·(raw − offset)")]
    quality: QualityMetrics | None
    failures: tuple[FailureReason, ...]
    gyro: Annotated[
        GyroSummary | None,
        Field(description="the gyros over the latest run's still poses: bias, noise, slope vs g"),
    ]

    @classmethod
    def of(cls, run: RunSummary) -> "UnitCalibration":
        """The unit's state given its latest run."""
        cal = run.coefficients
        return cls(
            serial=run.serial,
            verdict=run.verdict,
            run_id=run.run_id,
            calibrated_at=run.finished_at,
            station_id=run.station_id,
            operator_id=run.operator_id,
            software_version=run.software_version,
            model=run.model,
            limits=run.limits,
            offset=cal.offset if cal else None,
            sensitivity=cal.sensitivity if cal else None,
            matrix=cal.matrix if cal else None,
            quality=run.quality,
            failures=run.failures,
            gyro=run.gyro,
        )


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
