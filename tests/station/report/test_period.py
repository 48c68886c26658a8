"""Reading the report's time bounds."""

from datetime import UTC, datetime

import pytest

from station.errors import InputError
from station.report.period import parse_moment, start_of_day


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
