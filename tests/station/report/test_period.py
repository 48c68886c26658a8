"""Reading the report's time bounds."""

from datetime import UTC, datetime, timedelta, timezone

import pytest
from hypothesis import given
from hypothesis import strategies as st

from db.reports import split_days
from station.domain.errors import InputError
from station.report.period import (
    EARLIEST,
    LATEST,
    check_order,
    parse_moment,
    parse_period,
    plant_zone,
    start_of_day,
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


def test_start_of_day_is_midnight_utc() -> None:
    assert start_of_day(datetime(2026, 11, 2, 23, 59, tzinfo=UTC)) == datetime(
        2026, 11, 2, tzinfo=UTC
    )


@pytest.mark.parametrize(
    "text",
    [
        "9999-12-31T23:00:00-05:00",  # past year 9999 in UTC
        "0001-01-01T00:00:00+01:00",  # before year 1 in UTC
        "9999-12-31T00:00:01",  # no whole day after it
        "0001-01-01",  # no whole day before it
    ],
)
def test_a_moment_out_of_range_names_the_option_and_the_range(text: str) -> None:
    with pytest.raises(
        InputError, match=r"^--from '.*' is out of range: .*0001-01-02 to 9999-12-31"
    ):
        parse_moment(text, name="--from")


@given(
    naive=st.datetimes(),
    offset_min=st.integers(-23 * 60 - 59, 23 * 60 + 59),
)
def test_any_iso_moment_is_its_utc_instant_or_out_of_range(
    naive: datetime, offset_min: int
) -> None:
    zone = timezone(timedelta(minutes=offset_min))
    text = naive.replace(tzinfo=zone).isoformat()
    # The instant, as a distance from EARLIEST (timedelta holds the whole range).
    since_earliest = naive - EARLIEST.replace(tzinfo=None) - timedelta(minutes=offset_min)
    inside = timedelta(0) <= since_earliest <= LATEST - EARLIEST
    if not inside:
        with pytest.raises(InputError, match="out of range"):
            parse_moment(text, name="from")
        return
    moment = parse_moment(text, name="from")
    assert moment.tzinfo == UTC
    assert moment - EARLIEST == since_earliest


def test_the_report_can_split_the_widest_period_into_days() -> None:
    days, edges = split_days(EARLIEST, LATEST)
    assert days is not None
    assert edges == []
    second = timedelta(seconds=1)
    days, edges = split_days(EARLIEST + second, LATEST - second)
    assert edges == [
        (EARLIEST + second, EARLIEST + timedelta(days=1)),
        (LATEST - timedelta(days=1), LATEST - second),
    ]


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
    check_order(EARLIEST, LATEST)
    with pytest.raises(InputError, match=r"^from 9999-12-31 00:00\+00:00 is not before to 0001"):
        check_order(LATEST, EARLIEST, names=("from", "to"))
    with pytest.raises(InputError, match="the period holds nothing"):
        check_order(EARLIEST, EARLIEST)


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
    assert start_of_day(now, zone).isoformat() == midnight


def test_dates_without_a_zone_are_the_plants_and_an_unknown_zone_is_refused() -> None:
    assert parse_moment("2026-11-02", name="--from", zone="Asia/Kolkata").isoformat() == (
        "2026-11-01T18:30:00+00:00"
    )
    assert parse_moment("2026-11-02T14:00Z", name="--from", zone="Asia/Kolkata").hour == 14
    assert plant_zone("Europe/Berlin") == "Europe/Berlin"
    with pytest.raises(InputError, match="time zone 'Mars/Olympus' is unknown"):
        plant_zone("Mars/Olympus")
