"""What a certificate states about its run: number, method and sources, conditions, the
laboratory, the item as found and as left, its statements and end."""

from datetime import UTC, datetime, time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.product.laboratory import Laboratory, load_laboratory
from station.domain.product.limits import load_profile
from station.domain.quality.shifts import shift_start
from station.domain.record.records import RunRecord, StoredRun
from station.report.certificate import (
    as_found,
    as_left,
    document_number,
    mean_temperature,
    method,
)
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


#: A unit as it leaves its maker: the nominal zero and sensitivity, never written.
FACTORY = {
    "written": False,
    "offset": [2048.0, 2048.0, 2048.0],
    "matrix": [[1 / 819.2, 0.0, 0.0], [0.0, 1 / 819.2, 0.0], [0.0, 0.0, 1 / 819.2]],
}
LAB = Laboratory(
    name="Putter Works Calibration Lab",
    address="12 Gangnam-daero, Seoul",
    location="line 1, building B",
    customer="Putter Works Quality",
    gravity_m_s2=9.79966,
    traceability="g from the 2019 KRISS absolute gravity survey of the plant",
)


def _stored(run: RunRecord) -> StoredRun:
    return StoredRun.model_validate({**run.model_dump(), "received_at": run.finished_at})


def _found(run: RunRecord, accelerometer: dict[str, object] = FACTORY) -> RunRecord:
    found = {"read_at": run.started_at.isoformat(), "accelerometer": accelerometer}
    return RunRecord.model_validate({**run.model_dump(mode="json"), "as_found": found})


@settings(max_examples=60, deadline=None)
@given(
    shift=st.floats(1.0, 50.0) | st.floats(-50.0, -1.0),
    axis=st.integers(0, 2),
)
def test_as_found_error_is_what_a_wrong_offset_makes_of_the_fit_poses(
    shift: float, axis: int
) -> None:
    """Coefficients that fit the poses make no |g| error; an offset wrong by δ counts on
    one axis makes at most |δ|/s (triangle inequality) and nearly that on the pose along
    the axis (first order: δ/s times its direction's component, ≥ 0.997)."""
    run = make_record()
    cal = run.coefficients
    assert cal is not None
    offset = list(cal.offset.as_tuple())
    offset[axis] += shift
    wrong = {"written": True, "offset": offset, "matrix": [list(r) for r in cal.matrix]}
    found, left = as_found(_found(run, wrong)), as_left(run)
    assert found is not None
    assert left is not None
    assert left.error_mg < 1e-6
    bound = abs(shift) / cal.sensitivity.as_tuple()[axis] * 1000.0
    assert 0.9 * bound <= found.error_mg <= bound + 1e-9
    assert found.written
    assert found.offset[axis] == offset[axis]


def test_the_certificate_states_the_laboratory_the_item_as_found_and_as_left() -> None:
    run = _found(make_record())
    poses = [p.model_copy(update={"temperature_c": 23.25 + 0.5 * p.index}) for p in run.poses]
    run = run.model_copy(update={"poses": tuple(poses)})
    issued = datetime(2026, 11, 3, 9, 0, tzinfo=UTC)
    page = certificate_page(_stored(run), load_profile(), issued, laboratory=LAB)
    for value in (LAB.name, LAB.address, LAB.location, LAB.customer, LAB.traceability):
        assert f"{value}" in page
    assert "g = 9.79966 m/s²" in page
    assert "temperature 23.25 … 26.25 °C" in page  # the poses' range, not one value
    assert "held its factory defaults (never calibrated)" in page
    assert f'<td class="received">{run.started_at:%Y-%m-%d %H:%M}' in page
    assert '<td class="issued">2026-11-03 09:00' in page
    found = page.split('class="coefficient-state as-found"')[1].split("</table>")[0]
    assert f"<td>{number(2048.0, 8)}</td>" in found
    assert "(factory defaults)" in found
    left = page.split('class="coefficient-state as-left"')[1].split("</table>")[0]
    assert f"<td>{number(2081.9, 8)}</td>" in left
    assert "The results relate only to the item calibrated." in page
    assert "not signed by an authorised signatory" in page
    assert page.index('id="end-mark"') > page.index("Earlier runs")
    assert "— end of certificate —" in page
    number_ = document_number(run)
    assert f'@top-left {{ content: "Calibration certificate {number_}"' in page
    assert 'counter(page) " / " counter(pages)' in page


def test_a_run_from_before_as_found_says_not_recorded_and_an_unnamed_lab_not_configured() -> None:
    run = make_record()
    page = certificate_page(_stored(run), load_profile(), run.finished_at)
    assert '<td class="received">not recorded</td>' in page
    assert '<td class="condition">not recorded</td>' in page
    assert '<p class="as-found">as found: not recorded</p>' in page
    assert '<td class="laboratory">not configured</td>' in page
    assert '<td class="customer">not configured</td>' in page
    failed = _stored(make_record(verdict="fail"))
    report = certificate_page(failed, load_profile(), failed.finished_at)
    assert "as left: not stated: the run did not end in a verified write-back" in report
    assert "— end of report —" in report


def test_a_laboratory_file_that_is_not_one_is_one_line(tmp_path: Path) -> None:
    good = tmp_path / "station.toml"
    good.write_text('station_id = "st-1"\n[laboratory]\nname = "Lab"\ngravity_m_s2 = 9.8\n')
    assert load_laboratory(good) == Laboratory(name="Lab", gravity_m_s2=9.8)
    for text, says in (
        ('station_id = "st-1"\n', "no [laboratory] table"),
        ("[laboratory]\nnmae = 'Lab'\n", "[laboratory]: nmae: Extra inputs are not permitted"),
        ("[laboratory]\ngravity_m_s2 = 98.0\n", "gravity_m_s2"),
        ("[laboratory\n", "not valid TOML"),
    ):
        bad = tmp_path / "bad.toml"
        bad.write_text(text)
        with pytest.raises(InputError) as caught:
            load_laboratory(bad)
        assert says in str(caught.value)
        assert "\n" not in str(caught.value)
