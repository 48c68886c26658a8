"""``/api/v1/units/{serial}/gyro``: a unit's gyro error-model fit and still-pose figures."""

import logging
from datetime import UTC, datetime

from fastapi import APIRouter, HTTPException, Response, status

from api.deps import LabDep, ReaderDep, RepositoryDep
from api.responses import json_response, problems
from api.routes.units import SerialPath
from api.schemas import GyroFitSubmission, UnitGyro
from station.domain.record.records import GyroFitRecord

log = logging.getLogger(__name__)

router = APIRouter(prefix="/units", tags=["gyro"])
#: Storing a fit: a lab key only (a station's key answers 403).
submissions = APIRouter(prefix="/units", tags=["gyro"])


@router.get(
    "/{serial}/gyro",
    response_model=UnitGyro,
    responses=problems(404, _404="no gyro fit and no run of this serial"),
)
async def get_unit_gyro(serial: SerialPath, repository: ReaderDep) -> Response:
    """The unit's latest gyro fit (for compensation) and its latest run's still-pose gyros."""
    fit = await repository.run(lambda r: r.latest_gyro_fit(serial))
    latest = await repository.run(lambda r: r.latest_for_serial(serial))
    if fit is None and latest is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no gyro fit and no run of serial {serial}")
    return json_response(UnitGyro(serial=serial, fit=fit, still=latest.gyro if latest else None))


@submissions.post(
    "/{serial}/gyro",
    status_code=status.HTTP_201_CREATED,
    response_model=GyroFitRecord,
    responses=problems(400, 401, 403, _403="a station's key: gyro fits need a lab key"),
)
async def submit_unit_gyro(
    serial: SerialPath,
    submission: GyroFitSubmission,
    lab: LabDep,
    repository: RepositoryDep,
) -> Response:
    """Store a gyro fit of the unit (``calstation gyro fit LOG --json`` as ``report``)."""
    fit = GyroFitRecord(
        serial=serial,
        fitted_at=datetime.now(UTC),
        source=submission.source,
        report=submission.report,
        dwells=submission.dwells,
    )
    async with repository.session.begin():
        await repository.run(lambda r: r.add_gyro_fit(fit))
    log.info("gyro fit of %s from %s stored by lab %s", serial, fit.source, lab)
    return json_response(fit, status.HTTP_201_CREATED)
