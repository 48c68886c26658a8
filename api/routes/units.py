"""``/api/v1/units``: a unit's current calibration and its history."""

from typing import Annotated

from fastapi import APIRouter, HTTPException, Path, Response, status

from api.deps import ReaderDep, UnitLookupsDep
from api.responses import json_response, problems
from api.schemas import RunList
from station.domain.record.records import SERIAL_PATTERN
from station.domain.record.unit_state import UnitCalibration

router = APIRouter(
    prefix="/units",
    tags=["units"],
    responses=problems(404, _404="no run of this serial number"),
)

SerialPath = Annotated[str, Path(pattern=SERIAL_PATTERN, description="the unit's serial number")]


def _unknown(serial: str) -> HTTPException:
    return HTTPException(status.HTTP_404_NOT_FOUND, f"no calibration run of serial {serial}")


@router.get("/{serial}", response_model=UnitCalibration)
async def get_unit(serial: SerialPath, lookups: UnitLookupsDep) -> Response:
    """The unit's current calibration: the verdict and coefficients of its latest run."""
    calibration = await lookups.get(serial)
    if calibration is None:
        raise _unknown(serial)
    return Response(calibration, media_type="application/json")


@router.get("/{serial}/runs", response_model=RunList)
async def get_unit_runs(serial: SerialPath, repository: ReaderDep) -> Response:
    """Every run of the unit, oldest first (the first one counts for first-pass yield)."""
    runs = await repository.run(lambda r: r.history(serial))
    if not runs:
        raise _unknown(serial)
    return json_response(RunList(data=runs, count=len(runs)))
