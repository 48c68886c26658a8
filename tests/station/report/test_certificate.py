"""What a certificate states about its run: number, method and sources, conditions."""

from datetime import UTC, datetime, time

from station.domain.limits import load_profile
from station.domain.quality.shifts import shift_start
from station.domain.records import StoredRun
from station.report.certificate import document_number, mean_temperature, method
from station.report.formatting import number
from station.report.html import certificate_page
from tests.db.records import make_record


def test_the_document_number_is_the_run_ids_and_its_start_year() -> None:
    run = make_record(started_at=datetime(2027, 1, 1, 0, 30, tzinfo=UTC))
    assert document_number(run) == f"CAL-2027-{run.run_id.hex[:12].upper()}"
    assert document_number(run) == document_number(run.model_copy())
    failed = make_record(verdict="fail")
    assert document_number(failed).startswith("FR-2026-")
    assert document_number(failed) != document_number(make_record(verdict="fail"))


def test_the_method_cites_tedaldi_where_the_nine_parameter_or_gyro_fit_applies() -> None:
    six = dict(method(make_record()))
    assert "[Song2006]" in six["accelerometer"]
    assert "[Tedaldi2014]" not in str(six)
    nine = dict(method(make_record(model="nine")))
    assert "[Tedaldi2014]" in nine["accelerometer"]
    assert "ILAC-G8" in nine["decision rule"]
    assert "simple" in nine["decision rule"]
    guarded = dict(method(make_record(decision_rule="guarded")))
    assert "guard band w = U" in guarded["decision rule"]


def test_the_conditions_are_the_mean_temperature_of_the_poses() -> None:
    run = make_record()
    poses = [p.model_copy(update={"temperature_c": 20.0 + p.index}) for p in run.poses]
    assert mean_temperature(run.model_copy(update={"poses": tuple(poses)})) == 23.0
    none = [p.model_copy(update={"temperature_c": None}) for p in run.poses]
    assert mean_temperature(run.model_copy(update={"poses": tuple(none)})) is None


def test_a_moment_s_shift_starts_at_its_plant_shift_or_its_plant_day() -> None:
    starts = (time(6), time(14), time(22))
    at = datetime(2026, 11, 2, 4, 30, tzinfo=UTC)  # 13:30 in Seoul: the 06:00 shift
    assert shift_start(at, "Asia/Seoul", starts) == datetime(2026, 11, 1, 21, tzinfo=UTC)
    night = datetime(2026, 11, 2, 19, 0, tzinfo=UTC)  # 04:00 next day: the 22:00 shift
    assert shift_start(night, "Asia/Seoul", starts) == datetime(2026, 11, 2, 13, tzinfo=UTC)
    assert shift_start(at, "Asia/Seoul", ()) == datetime(2026, 11, 1, 15, tzinfo=UTC)


#: A whole unit's gyro matrix as a run records it.
GYRO_MATRIX = {
    "matrix": [[1.004, 0.002, -0.001], [0.001, 0.997, 0.003], [-0.002, 0.001, 1.002]],
    "standard_errors": [[6e-5, 5e-5, 5e-5], [5e-5, 6e-5, 5e-5], [5e-5, 5e-5, 6e-5]],
    "bias_dps": {"x": 0.01, "y": -0.02, "z": 0.005},
    "residual_rms_deg": 0.01,
    "condition_number": 3.0,
}


def test_a_whole_unit_s_certificate_cites_tedaldi_and_prints_k_with_its_u() -> None:
    u = {"k": 2.0, "gyro_matrix": [[0.000171, 0.000132, 0.000133]] * 3}
    run = make_record(model="nine", gyro_matrix=GYRO_MATRIX, uncertainty=u)
    assert "[Tedaldi2014]" in dict(method(run))["gyro matrix K"]
    stored = StoredRun.model_validate({**run.model_dump(), "received_at": run.finished_at})
    page = certificate_page(stored, load_profile(), stored.finished_at)
    k = page.split("<h2>Gyro matrix K</h2>")[1].split("</table>")[0]
    assert k.count(f"<td>{number(0.000171, 2)}</td>") == 3
    assert f"<td>{number(6e-5, 2)}</td>" not in k  # U, not the fit's 1-σ
    assert "coverage factor k = 2" in k
    assert "<tr><th>gyro matrix K</th><td>fitted from the moves" in page
