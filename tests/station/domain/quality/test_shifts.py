"""The plant's shifts: parsed start times, and the shifts a period touches in a zone."""

from datetime import UTC, datetime, time, timedelta
from itertools import pairwise
from zoneinfo import ZoneInfo

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.quality.shifts import MAX_SHIFTS, parse_shifts, plant_shifts

ZONES = ["UTC", "Europe/Berlin", "America/New_York", "Pacific/Kiritimati", "Australia/Lord_Howe"]
moments = st.datetimes(
    min_value=datetime(2025, 1, 1), max_value=datetime(2027, 12, 31), timezones=st.just(UTC)
)
starts = st.lists(
    st.builds(time, st.integers(0, 23), st.sampled_from([0, 15, 30, 45])),
    min_size=1,
    max_size=4,
    unique=True,
)


def test_start_times_are_read_and_sorted() -> None:
    assert parse_shifts(" 22:00, 06:00 ,14:00") == (time(6), time(14), time(22))
    assert parse_shifts("") == ()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("06:00,25:00", "shift start '25:00' is not a time of day"),
        ("early", "shift start 'early' is not a time of day"),
        ("06:00,06:00", "shift start '06:00' is given twice"),
        ("06:00:30", "give hours and minutes only"),
        (",".join(f"{h:02d}:{m:02d}" for h in range(13) for m in (0, 30)), f"at most {MAX_SHIFTS}"),
    ],
)
def test_a_bad_start_time_is_named(text: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        parse_shifts(text)


@given(
    zone=st.sampled_from(ZONES),
    at=starts,
    start=moments,
    hours=st.floats(0, 24 * 5),
)
def test_the_shifts_tile_the_period_with_their_local_start_times(
    zone: str, at: list[time], start: datetime, hours: float
) -> None:
    end = start + timedelta(hours=hours)
    shifts = plant_shifts(start, end, zone, sorted(at), latest=10_000)
    assert shifts[0].start <= start < shifts[0].end
    assert shifts[-1].start <= end < shifts[-1].end
    local = ZoneInfo(zone)
    names = {t.strftime("%H:%M") for t in at}
    for shift, following in pairwise(shifts):
        assert shift.end == following.start  # no gap, no overlap
    for shift in shifts:
        assert shift.start < shift.end
        assert shift.name in names
        wall = shift.start.astimezone(local)
        # The day it starts on, at its start time (an hour later in a skipped hour).
        started = datetime.combine(shift.day, time.fromisoformat(shift.name), tzinfo=local)
        assert wall.replace(tzinfo=None) - started.replace(tzinfo=None) in (
            timedelta(0),
            timedelta(minutes=30),  # Lord Howe skips half an hour
            timedelta(hours=1),
        )


def test_a_night_shift_belongs_to_the_day_it_started_on() -> None:
    # 02:00 on 11-02 in Berlin is in the 22:00 shift of 11-01; it ends at 06:00 local.
    moment = datetime(2026, 11, 2, 1, tzinfo=UTC)
    [night] = plant_shifts(moment, moment, "Europe/Berlin", [time(6), time(14), time(22)], 10)
    assert (night.day.isoformat(), night.name) == ("2026-11-01", "22:00")
    assert (night.start, night.end) == (
        datetime(2026, 11, 1, 21, tzinfo=UTC),
        datetime(2026, 11, 2, 5, tzinfo=UTC),
    )


def test_the_shift_across_the_clock_change_lasts_an_hour_less() -> None:
    # Berlin springs forward at 02:00 on 2026-03-29: the 22:00 shift lasts 7 hours.
    moment = datetime(2026, 3, 29, 1, tzinfo=UTC)
    [night] = plant_shifts(moment, moment, "Europe/Berlin", [time(6), time(14), time(22)], 10)
    assert night.end - night.start == timedelta(hours=7)


def test_only_the_latest_shifts_are_kept() -> None:
    # 11-02 00:00 to 11-05 00:00 touches seven shifts, from 11-01 18:00 to 11-04 18:00.
    start = datetime(2026, 11, 2, tzinfo=UTC)
    shifts = plant_shifts(start, start + timedelta(days=3), "UTC", [time(6), time(18)], 4)
    assert [(s.day.day, s.name) for s in shifts] == [
        (3, "06:00"),
        (3, "18:00"),
        (4, "06:00"),
        (4, "18:00"),
    ]
    assert plant_shifts(start, start, "UTC", [], 4) == []
