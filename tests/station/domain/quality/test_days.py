"""The plant's calendar over every moment of the years 1…9999: days, shifts and the
report's bounds in any zone, clamped at the ends of the range (never overflowing)."""

from datetime import UTC, date, datetime, time, timedelta
from itertools import pairwise
from zoneinfo import ZoneInfo

from hypothesis import example, given
from hypothesis import strategies as st

from station.domain.quality.days import (
    FIRST,
    LAST,
    day_end,
    day_start,
    midnight,
    plant_date,
    plant_days,
    plant_time,
    step,
    utc,
)
from station.domain.quality.shifts import plant_shifts, shift_name, shift_start
from station.report import formatting
from station.report.period import parse_moment

#: The zones at the extremes (+14, −12, +14 since 1994 only), with daylight saving time
#: (both hemispheres, a half-hour change) and a half-hour offset.
ZONES = [
    "UTC",
    "Pacific/Kiritimati",
    "Etc/GMT-14",
    "Etc/GMT+12",
    "Europe/Berlin",
    "America/New_York",
    "Australia/Lord_Howe",
    "Asia/Kolkata",
]
#: Zones whose offset never changes: their wall clock reads every instant once.
FIXED_ZONES = ["UTC", "Etc/GMT-14", "Etc/GMT+12", "Etc/GMT-5"]
EPSILON = timedelta(microseconds=1)

#: Moments strictly inside the range, with the first and last days drawn as often as the rest.
moments = st.one_of(
    st.datetimes(min_value=datetime.min + EPSILON, max_value=datetime.max - EPSILON),
    st.datetimes(min_value=datetime.min + EPSILON, max_value=datetime.min + timedelta(days=3)),
    st.datetimes(min_value=datetime.max - timedelta(days=3), max_value=datetime.max - EPSILON),
).map(lambda naive: naive.replace(tzinfo=UTC))
dates = st.one_of(
    st.dates(),
    st.dates(max_value=date.min + timedelta(days=3)),
    st.dates(min_value=date.max - timedelta(days=3)),
)
#: Shift plans: one to four start times, a night shift crossing midnight among them
#: whenever the last start is not at midnight.
shift_plans = st.lists(
    st.builds(time, st.integers(0, 23), st.sampled_from([0, 30])),
    min_size=1,
    max_size=4,
    unique=True,
).map(sorted)


def _outside(moment: datetime, zone: str) -> bool:
    """Whether the zone's wall clock at ``moment`` lies outside the years 1…9999."""
    offset = ZoneInfo(zone).utcoffset(moment.replace(tzinfo=None)) or timedelta()
    try:
        moment.replace(tzinfo=None) + offset
    except OverflowError:
        return True
    return False


@given(moment=moments, zone=st.sampled_from(ZONES))
def test_a_moment_is_on_the_plants_clock_or_in_utc_at_the_ends(moment: datetime, zone: str) -> None:
    local = plant_time(moment, zone)
    assert local == moment  # the same instant
    assert (local.tzinfo is UTC) == _outside(moment, zone)


@given(moment=moments, zone=st.sampled_from(ZONES))
def test_every_moment_lies_in_its_plant_day(moment: datetime, zone: str) -> None:
    day = plant_date(moment, zone)
    assert midnight(day, zone) <= moment < day_end(day, zone)
    assert day_start(moment, zone) == midnight(day, zone)


@given(day=dates, zone=st.sampled_from(ZONES))
def test_the_days_follow_one_another_from_the_first_moment_to_the_last(
    day: date, zone: str
) -> None:
    """Each day ends where the next starts (a date the zone skipped lasts no time)."""
    start, end = midnight(day, zone), day_end(day, zone)
    assert FIRST <= start <= end <= LAST
    assert (start == FIRST) == (day == date.min)
    assert end == (LAST if day == date.max else midnight(step(day, 1), zone))


@given(day=dates, days=st.integers(-4_000_000, 4_000_000))
def test_stepping_stops_at_the_first_and_last_dates(day: date, days: int) -> None:
    exact = day.toordinal() + days
    clamped = min(max(exact, date.min.toordinal()), date.max.toordinal())
    assert step(day, days) == date.fromordinal(clamped)


@given(moment=moments, zone=st.sampled_from(ZONES), hours=st.integers(-48, 48))
def test_a_wall_clock_time_reads_as_its_instant_or_the_end_on_its_side(
    moment: datetime, zone: str, hours: int
) -> None:
    """A local wall-clock time (a moment's, shifted some hours) as UTC."""
    naive = moment.replace(tzinfo=None)
    try:
        wall = naive + timedelta(hours=hours)
    except OverflowError:
        wall = datetime.max if hours > 0 else datetime.min
    local = wall.replace(tzinfo=ZoneInfo(zone))
    offset = local.utcoffset() or timedelta()
    instant = utc(local)
    assert FIRST <= instant <= LAST
    exact = wall - FIRST.replace(tzinfo=None) - offset  # from FIRST: a timedelta holds it
    if timedelta() <= exact <= LAST - FIRST:
        assert instant - FIRST == exact
    else:
        assert instant == (FIRST if exact < timedelta() else LAST)


@given(
    start=moments,
    end=moments,
    zone=st.sampled_from(ZONES),
    latest=st.integers(1, 40),
)
def test_the_plant_days_of_a_period_are_consecutive_and_end_on_its_last(
    start: datetime, end: datetime, zone: str, latest: int
) -> None:
    start, end = min(start, end), max(start, end)
    days = plant_days(start, end, zone, latest)
    assert days[-1] == plant_date(end, zone)
    assert 1 <= len(days) <= latest
    assert all(b == step(a, 1) for a, b in pairwise(days))
    assert days[0] == plant_date(start, zone) or len(days) == latest


@given(
    start=moments,
    hours=st.integers(0, 72),
    zone=st.sampled_from(ZONES),
    starts=shift_plans,
)
# Kiritimati skipped 1994-12-31 (from −10:00 to +14:00): that date has no shifts.
@example(
    start=datetime(1994, 12, 30, 12, tzinfo=UTC),
    hours=72,
    zone="Pacific/Kiritimati",
    starts=[time(6), time(14), time(22)],
)
def test_the_shifts_tile_any_period_of_the_range(
    start: datetime, hours: int, zone: str, starts: list[time]
) -> None:
    end = start + min(timedelta(hours=hours), LAST - EPSILON - start)
    shifts = plant_shifts(start, end, zone, starts, latest=10_000)
    assert shifts[0].start <= start < shifts[0].end
    assert shifts[-1].start <= end < shifts[-1].end
    names = {shift_name(at) for at in starts}
    for shift in shifts:
        assert FIRST <= shift.start < shift.end <= LAST
        assert shift.name in names
        assert plant_date(shift.start, zone) == shift.day
    for before, after in pairwise(shifts):
        assert before.end == after.start


@given(moment=moments, zone=st.sampled_from(ZONES), starts=shift_plans)
def test_every_moment_has_one_shift_that_started_at_or_before_it(
    moment: datetime, zone: str, starts: list[time]
) -> None:
    (shift,) = plant_shifts(moment, moment, zone, starts, latest=10_000)
    assert shift.start <= moment < shift.end
    assert shift_start(moment, zone, starts) == shift.start
    assert shift_start(moment, zone, []) == day_start(moment, zone)


@given(moment=moments, zone=st.sampled_from(ZONES))
def test_every_moment_is_shown_in_every_zone(moment: datetime, zone: str) -> None:
    """To the second on the plant's clock (its ISO date, the year in four digits), naming
    the zone it is shown in."""
    local = plant_time(moment, zone)
    wall, name = formatting.moment(moment, zone).rsplit(" ", 1)
    assert datetime.fromisoformat(wall) == local.replace(tzinfo=None, microsecond=0)
    assert name == local.tzname()
    assert formatting.clock(moment, zone) == wall[5:16]


@given(moment=moments, zone=st.sampled_from(FIXED_ZONES))
def test_a_moment_in_the_reports_form_reads_back_as_itself(moment: datetime, zone: str) -> None:
    """The form's and links' bounds (:func:`formatting.field`) are exact, at the ends too."""
    assert parse_moment(formatting.field(moment, zone), name="from", zone=zone) == moment
