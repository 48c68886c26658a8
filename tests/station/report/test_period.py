"""Reading the report's time bounds."""

from datetime import UTC, datetime

import pytest

from station.errors import InputError
from station.report.period import MOMENT_MAX, MOMENT_MIN, check_range, parse_moment, start_of_day


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
    ["9999-12-31T23:00:00-05:00", "0001-01-01T00:00:00+01:00", "9999-12-31T00:00:01Z"],
)
def test_a_moment_outside_the_years_after_its_zone_names_the_option(text: str) -> None:
    with pytest.raises(InputError, match=r"^--from '.*' is outside 0001-01-01 … 9999-12-31"):
        parse_moment(text, name="--from")


def test_the_last_and_first_moments_are_kept() -> None:
    assert parse_moment("9999-12-31", name="to") == MOMENT_MAX
    assert parse_moment("0001-01-01T00:00:00Z", name="from") == MOMENT_MIN


def test_a_start_after_the_end_names_both() -> None:
    check_range(MOMENT_MIN, MOMENT_MIN, names="--from/--to")
    with pytest.raises(InputError, match=r"^--from 9999-12-31 00:00 UTC is after --to 0001-01-01"):
        check_range(MOMENT_MAX, MOMENT_MIN, names="--from/--to")
