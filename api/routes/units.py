"""``/api/v1/units``: a unit's current calibration and its history."""

from typing import Annotated

from fastapi import APIRouter, Depends, HTTPException, Path, status

from api.deps import RepositoryDep, require_reader
from api.schemas import Problem, RunList, UnitCalibration
from station.records import SERIAL_PATTERN

router = APIRouter(
    prefix="/units",
    tags=["units"],
    dependencies=[Depends(require_reader)],
    responses={404: {"model": Problem, "description": "no run of this serial number"}},
)

SerialPath = Annotated[str, Path(pattern=SERIAL_PATTERN, description="the unit's serial number")]


def _unknown(serial: str) -> HTTPException:
    return HTTPException(status.HTTP_404_NOT_FOUND, f"no calibration run of serial {serial}")


@router.get("/{serial}")
def get_unit(serial: SerialPath, repository: RepositoryDep) -> UnitCalibration:
    """The unit's current calibration: the verdict and coefficients of its latest run."""
    latest = repository.latest_for_serial(serial)
    if latest is None:
        raise _unknown(serial)
    return UnitCalibration.of(latest)


@router.get("/{serial}/runs")
def get_unit_runs(serial: SerialPath, repository: RepositoryDep) -> RunList:
    """Every run of the unit, oldest first (the first one counts for first-pass yield)."""
    runs = repository.history(serial)
    if not runs:
        raise _unknown(serial)
    return RunList(data=runs, count=len(runs))
