"""What a unit's certificate (or failure report) is made of, read in one place: the
results server's page (``api.routes.reports``) and the station's own
(``calstation certificate issue``) read it alike."""

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import time

from db.store.limits_profiles import stored_profiles
from db.store.repository import RunRepository
from db.store.signatures import signature_of
from station.domain.product.limits import LimitsProfile
from station.domain.quality.shifts import shift_start
from station.domain.record.records import GyroFitRecord, HoldReview, RunSummary, StoredRun
from station.domain.record.signature import Signature
from station.domain.record.unit_state import counts


@dataclass(frozen=True)
class CertificateInputs:
    """The unit's latest run that counts, the unit's runs before it, the run's limits
    profile as stored (None: never sent), the unit's latest gyro fit, that shift's
    golden-unit check at the run's station, the unit's reviews (a failed run's) and the
    certificate's signature."""

    run: StoredRun
    earlier: Sequence[RunSummary]
    profile: LimitsProfile | None
    gyro_fit: GyroFitRecord | None
    golden: RunSummary | None
    reviews: Sequence[HoldReview]
    #: The signatory's signature of the certificate; None: not signed.
    signature: Signature | None


def certificate_run(
    repository: RunRepository, serial: str
) -> tuple[StoredRun, list[RunSummary]] | None:
    """The unit's latest run that counts (an operator's abort does not), as the report's,
    and the unit's runs before it."""
    runs = repository.history(serial)
    counted = [run for run in runs if counts(run)] or runs
    if not counted:
        return None
    run = repository.get(counted[-1].run_id)
    assert run is not None
    return run, runs[: runs.index(counted[-1])]


def certificate_inputs(
    repository: RunRepository, serial: str, zone: str, shifts: Sequence[time]
) -> CertificateInputs | None:
    """Everything the certificate of ``serial`` shows; None when no run of it is stored.
    ``zone`` and ``shifts``: the plant's, which say the shift whose golden-unit check is
    the run's reference."""
    found = certificate_run(repository, serial)
    if found is None:
        return None
    run, earlier = found
    profile = stored_profiles(repository.session, [run.limits.sha256]).get(run.limits.sha256)
    since = shift_start(run.started_at, zone, shifts)
    return CertificateInputs(
        run=run,
        earlier=earlier,
        profile=profile,
        gyro_fit=repository.latest_gyro_fit(serial),
        golden=repository.latest_golden(run.station_id, since, run.started_at),
        reviews=repository.reviews(serial) if run.verdict == "fail" else [],
        signature=signature_of(repository.session, run.run_id),
    )
