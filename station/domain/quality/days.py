"""The plant's days: local calendar days in the plant's time zone, as UTC spans.

Stored times are UTC; the plant reads its day in its own zone (IANA name, through
:mod:`zoneinfo`, daylight saving time included: a day may last 23 or 25 hours). A day
is numbered like the roll-ups' UTC days, days from 1970-01-01 to its date.
"""

from datetime import UTC, date, datetime, time, timedelta
from zoneinfo import ZoneInfo

EPOCH_DATE = date(1970, 1, 1)


def midnight(day: date, zone: str) -> datetime:
    """The start of the plant's ``day`` in UTC."""
    return datetime.combine(day, time(), tzinfo=ZoneInfo(zone)).astimezone(UTC)


def plant_date(moment: datetime, zone: str) -> date:
    """The plant's date at ``moment``."""
    return moment.astimezone(ZoneInfo(zone)).date()


def day_number(day: date) -> int:
    """Days from 1970-01-01 to ``day`` (the roll-ups' ``day``)."""
    return (day - EPOCH_DATE).days


def plant_days(start: datetime, end: datetime, zone: str, latest: int) -> list[date]:
    """The plant's days that ``[start, end]`` touches, at most the ``latest`` of them."""
    first, last = plant_date(start, zone), plant_date(end, zone)
    first = max(first, last - timedelta(days=latest - 1))
    return [first + timedelta(days=i) for i in range((last - first).days + 1)]


def is_utc(zone: str) -> bool:
    """Whether the plant's days are the UTC days (``UTC`` or a zone always at +00:00)."""
    return zone in ("UTC", "Etc/UTC", "Etc/GMT", "GMT", "Etc/Universal", "Universal", "Zulu")
