"""Public shapes of the API's answers (the run record itself is :mod:`station.records`)."""

from datetime import datetime
from typing import Annotated
from uuid import UUID

from pydantic import BaseModel, Field

from station.records import (
    FailureReason,
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
        )


class RunList(BaseModel):
    """A list of runs; ``next_cursor`` fetches the next page (``null`` on the last)."""

    data: list[RunSummary]
    count: int
    next_cursor: str | None = None
