"""The run record: what it accepts, what it refuses, and that JSON round-trips it exactly."""

from datetime import UTC, datetime, timedelta, timezone

import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydantic import ValidationError

from station.domain.record.records import RunRecord
from tests.db.records import T0, make_record

#: Offsets and sensitivities that keep every pose mean inside the ADC range.
offsets = st.floats(min_value=1700.0, max_value=2400.0)


@given(
    offset=st.tuples(offsets, offsets, offsets),
    sensitivity=st.tuples(*[st.floats(min_value=600.0, max_value=1000.0)] * 3),
    verdict=st.sampled_from(["pass", "fail"]),
    minutes=st.integers(min_value=0, max_value=10**7),
)
def test_json_round_trip_is_exact(
    offset: tuple[float, float, float],
    sensitivity: tuple[float, float, float],
    verdict: str,
    minutes: int,
) -> None:
    record = make_record(
        offset=offset,
        sensitivity=sensitivity,
        verdict=verdict,
        started_at=T0 + timedelta(minutes=minutes),
    )
    assert RunRecord.model_validate_json(record.model_dump_json()) == record


def test_times_are_normalised_to_utc() -> None:
    local = datetime(2026, 11, 2, 17, 0, tzinfo=timezone(timedelta(hours=9)))
    record = make_record(started_at=local)
    assert record.started_at == datetime(2026, 11, 2, 8, 0, tzinfo=UTC)
    assert record.started_at.utcoffset() == timedelta(0)


def _payload(**changes: object) -> dict[str, object]:
    payload = make_record().model_dump(mode="json")
    payload.update(changes)
    return payload


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"started_at": "2026-11-02T08:00:00"}, "timezone"),
        ({"started_at": "0001-01-01T00:00:00+14:00"}, "outside the years"),
        ({"serial": "PT 01"}, "serial"),
        ({"serial": "PT\x0001"}, "serial"),
        ({"verdict": "maybe"}, "verdict"),
        ({"model": "twelve"}, "model"),
        ({"finished_at": "2026-11-02T07:00:00Z"}, "finished_at is before started_at"),
        ({"failures": [{"code": "x", "message": "m"}]}, "passing run has no failure"),
        ({"verdict": "fail"}, "failing run needs at least one failure"),
        ({"coefficients": None}, "passing run needs its coefficients"),
        ({"poses": []}, "poses"),
        ({"unexpected": 1}, "unexpected"),
    ],
)
def test_inconsistent_records_are_refused(changes: dict[str, object], message: str) -> None:
    with pytest.raises(ValidationError, match=message):
        RunRecord.model_validate(_payload(**changes))


def test_pose_means_must_be_adc_counts() -> None:
    payload = _payload()
    poses = payload["poses"]
    assert isinstance(poses, list)
    poses[2]["mean"]["y"] = 4096.0
    record = RunRecord.model_validate(payload)
    assert record.counts_beyond(4095) == (
        f"poses.2.mean: y 4096 outside the ADC range 0…4095 of {record.part_number}"
    )
    assert record.counts_beyond(65535) is None
    poses[2]["mean"]["y"] = 65536.0
    with pytest.raises(ValidationError, match="ADC range"):
        RunRecord.model_validate(payload)


def test_pose_indexes_must_number_the_poses() -> None:
    payload = _payload()
    poses = payload["poses"]
    assert isinstance(poses, list)
    poses[1]["index"] = 0
    with pytest.raises(ValidationError, match="pose indexes"):
        RunRecord.model_validate(payload)


def test_non_finite_numbers_and_control_characters_are_refused() -> None:
    with pytest.raises(ValidationError, match="finite"):
        RunRecord.model_validate_json(
            make_record()
            .model_dump_json()
            .replace('"residual_rms_mg":0.4', '"residual_rms_mg":NaN')
        )
    payload = _payload(failures=[{"code": "x", "message": "bad\nline"}], verdict="fail")
    with pytest.raises(ValidationError, match="control characters"):
        RunRecord.model_validate(payload)


def test_the_matrix_must_be_three_by_three() -> None:
    payload = _payload()
    coefficients = payload["coefficients"]
    assert isinstance(coefficients, dict)
    coefficients["matrix"] = [[1.0, 0.0], [0.0, 1.0]]
    with pytest.raises(ValidationError, match="3 rows of 3"):
        RunRecord.model_validate(payload)


def test_fit_poses_leave_out_the_verification_pose() -> None:
    record = make_record()
    assert [p.index for p in record.fit_poses()] == [0, 1, 2, 3, 4, 5]
