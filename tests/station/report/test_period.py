"""Reading the report's time bounds."""

from datetime import UTC, date, datetime, timedelta, timezone

import pytest
from hypothesis import given
from hypothesis import strategies as st

from db.report.queries import split_days
from station.domain.errors import InputError
from station.domain.quality.days import FIRST, LAST, day_number, day_start
from station.report.period import (
    check_order,
    parse_moment,
    parse_period,
    plant_zone,
)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("2026-11-02", datetime(2026, 11, 2, tzinfo=UTC)),
        ("2026-11-02T14:30", datetime(2026, 11, 2, 14, 30, tzinfo=UTC)),
        ("2026-11-02T14:30Z", datetime(2026, 11, 2, 14, 30, tzinfo=UTC)),
        ("2026-11-02T23:30+09:00", datetime(2026, 11, 2, 14, 30, tzinfo=UTC)),
    ],
)
def test_iso_dates_and_times_read_as_utc(text: str, expected: datetime) -> None:
    moment = parse_moment(text, name="--from")
    assert moment == expected
    assert moment.tzinfo == UTC


def test_anything_else_names_the_option() -> None:
    with pytest.raises(InputError, match=r"^--to '2026-13-01' is not an ISO date"):
        parse_moment("2026-13-01", name="--to")


@pytest.mark.parametrize(
    ("text", "zone"),
    [
        ("9999-12-31T23:00:00-05:00", "UTC"),  # past year 9999 in UTC
        ("0001-01-01T00:00:00+01:00", "UTC"),  # before year 1 in UTC
        ("9999-12-31T23:00", "Etc/GMT+12"),  # the plant's time, past 9999 in UTC
        ("0001-01-01T13:59", "Etc/GMT-14"),  # the plant's time (+14), before year 1
    ],
)
def test_a_moment_out_of_range_names_the_option_and_the_range(text: str, zone: str) -> None:
    with pytest.raises(
        InputError,
        match=r"^--from '.*' is out of range: give a moment from 0001-01-01T00:00:00\+00:00 "
        r"to 9999-12-31T23:59:59.999999\+00:00$",
    ):
        parse_moment(text, name="--from", zone=zone)


@pytest.mark.parametrize("zone", ["UTC", "Pacific/Kiritimati", "Etc/GMT+12", "Europe/Berlin"])
def test_the_first_and_last_dates_are_days_of_the_plant_in_any_zone(zone: str) -> None:
    """The plant's first day starts at the first moment whatever the zone; its last day's
    midnight is a moment of the range too."""
    assert parse_moment("0001-01-01", name="--from", zone=zone) == FIRST
    last = parse_moment("9999-12-31", name="--from", zone=zone)
    assert last.date() in (date(9999, 12, 30), date(9999, 12, 31))
    assert parse_moment("9999-12-31T23:59:59.999999Z", name="--to", zone=zone) == LAST


@given(
    naive=st.datetimes(),
    offset_min=st.integers(-23 * 60 - 59, 23 * 60 + 59),
)
def test_any_iso_moment_is_its_utc_instant_or_out_of_range(
    naive: datetime, offset_min: int
) -> None:
    zone = timezone(timedelta(minutes=offset_min))
    text = naive.replace(tzinfo=zone).isoformat()
    # The instant, as a distance from FIRST (timedelta holds the whole range).
    since_first = naive - FIRST.replace(tzinfo=None) - timedelta(minutes=offset_min)
    inside = timedelta(0) <= since_first <= LAST - FIRST
    if not inside:
        with pytest.raises(InputError, match="out of range"):
            parse_moment(text, name="from")
        return
    moment = parse_moment(text, name="from")
    assert moment.tzinfo == UTC
    assert moment - FIRST == since_first


def test_the_report_can_split_the_widest_period_into_days() -> None:
    last_midnight = datetime(9999, 12, 31, tzinfo=UTC)
    days, edges = split_days(FIRST, last_midnight)
    assert days is not None
    assert edges == []
    second = timedelta(seconds=1)
    days, edges = split_days(FIRST + second, LAST - second)
    assert edges == [(FIRST + second, FIRST + timedelta(days=1)), (last_midnight, LAST - second)]
    # A moment of the last date rounds up to the calendar's end: no whole day follows.
    days, edges = split_days(LAST - second, None)
    assert (days, edges) == ((day_number(date.max) + 1, None), [(LAST - second, LAST)])


def test_a_period_must_run_forwards() -> None:
    assert parse_period("2026-01-01", "2026-01-02") == (
        datetime(2026, 1, 1, tzinfo=UTC),
        datetime(2026, 1, 2, tzinfo=UTC),
    )
    assert parse_period(None, "2026-01-02")[0] is None
    for since, until in (("2026-02-01", "2026-01-01"), ("2026-01-01T05:00+05:00", "2026-01-01")):
        with pytest.raises(InputError, match=r"^from .* is not before to .*: the period holds"):
            parse_period(since, until, names=("from", "to"))


def test_the_api_checks_parsed_bounds_the_same_way() -> None:
    check_order(FIRST, LAST)
    with pytest.raises(InputError, match=r"^from 9999-12-31 23:59\+00:00 is not before to 0001"):
        check_order(LAST, FIRST, names=("from", "to"))
    with pytest.raises(InputError, match="the period holds nothing"):
        check_order(FIRST, FIRST)


@pytest.mark.parametrize(
    ("zone", "now", "midnight"),
    [
        # Berlin in winter (UTC+1): 00:30 local on 11-02 is 23:30 UTC on 11-01.
        ("Europe/Berlin", datetime(2026, 11, 1, 23, 30, tzinfo=UTC), "2026-11-01T23:00:00+00:00"),
        # The day DST ends there lasts 25 hours: its midnight was still at UTC+2.
        ("Europe/Berlin", datetime(2026, 10, 25, 12, 0, tzinfo=UTC), "2026-10-24T22:00:00+00:00"),
        ("America/New_York", datetime(2026, 11, 2, 3, 0, tzinfo=UTC), "2026-11-01T04:00:00+00:00"),
        ("UTC", datetime(2026, 11, 2, 3, 0, tzinfo=UTC), "2026-11-02T00:00:00+00:00"),
    ],
)
def test_today_is_the_plants_day(zone: str, now: datetime, midnight: str) -> None:
    assert day_start(now, zone).isoformat() == midnight


def test_dates_without_a_zone_are_the_plants_and_an_unknown_zone_is_refused() -> None:
    assert parse_moment("2026-11-02", name="--from", zone="Asia/Kolkata").isoformat() == (
        "2026-11-01T18:30:00+00:00"
    )
    assert parse_moment("2026-11-02T14:00Z", name="--from", zone="Asia/Kolkata").hour == 14
    assert plant_zone("Europe/Berlin") == "Europe/Berlin"
    with pytest.raises(InputError, match="time zone 'Mars/Olympus' is unknown"):
        plant_zone("Mars/Olympus")
