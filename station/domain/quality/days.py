"""The plant's days: local calendar days in the plant's time zone, as UTC spans.

Stored times are UTC; the plant reads its day in its own zone (IANA name, through
:mod:`zoneinfo`, daylight saving time included: a day may last 23 or 25 hours). A day
is numbered like the roll-ups' UTC days, days from 1970-01-01 to its date.

The calendar stops at the ends of what a time can hold, the years 1…9999 in UTC
(:data:`FIRST` … :data:`LAST`, where a station's own database may store a run whose clock
was wrong). It is clamped there, never overflowed:

- a moment whose wall-clock time in the plant's zone would leave the years 1…9999 (the
  first hours of year 1 west of UTC, the last hours of 9999 east of it) keeps its UTC
  time (:func:`plant_time`), so its plant date is the first or the last date;
- the plant's first day (0001-01-01) starts at :data:`FIRST` and its last
  (9999-12-31) ends at :data:`LAST`, whatever the zone (:func:`midnight`, :func:`day_end`);
- stepping a date past either end stays on it (:func:`step`); a local wall-clock time
  outside the range reads as the range's end on its side (:func:`utc`).
"""

from datetime import MINYEAR, UTC, date, datetime, time, timedelta, tzinfo
from zoneinfo import ZoneInfo

EPOCH_DATE = date(1970, 1, 1)

#: The first and last moments a time can hold (UTC): the ends of the plant's calendar.
FIRST = datetime.min.replace(tzinfo=UTC)
LAST = datetime.max.replace(tzinfo=UTC)


def utc(local: datetime) -> datetime:
    """The aware ``local`` in UTC; :data:`FIRST` or :data:`LAST` for a wall-clock time
    whose instant lies before or after the range."""
    try:
        return local.astimezone(UTC)
    except OverflowError:
        return FIRST if local.year == MINYEAR else LAST


def wall_clock(moment: datetime, zone: tzinfo | None = None) -> datetime:
    """``moment`` on the wall clock of ``zone`` (None: the system's local time); in UTC
    (``tzinfo`` exactly :data:`datetime.UTC`) when that wall-clock time would leave the
    years 1…9999."""
    try:
        return moment.astimezone(zone)
    except OverflowError:
        return moment.astimezone(UTC)


def plant_time(moment: datetime, zone: str) -> datetime:
    """``moment`` on the plant's wall clock (``zone``, an IANA name), as :func:`wall_clock`."""
    return wall_clock(moment, ZoneInfo(zone))


def plant_date(moment: datetime, zone: str) -> date:
    """The plant's date at ``moment`` (the first or last date where the zone's wall
    clock would leave the years 1…9999)."""
    return plant_time(moment, zone).date()


def step(day: date, days: int) -> date:
    """``days`` days after ``day`` (before it, if negative), stopping at the first and
    last dates."""
    try:
        return day + timedelta(days=days)
    except OverflowError:
        return date.max if days > 0 else date.min


def midnight(day: date, zone: str) -> datetime:
    """The start of the plant's ``day`` in UTC; :data:`FIRST` for the first date."""
    if day == date.min:
        return FIRST
    return utc(datetime.combine(day, time(), tzinfo=ZoneInfo(zone)))


def day_end(day: date, zone: str) -> datetime:
    """The end of the plant's ``day`` in UTC: the next day's start; :data:`LAST` for the
    last date."""
    return LAST if day == date.max else midnight(step(day, 1), zone)


def day_start(moment: datetime, zone: str) -> datetime:
    """The start (UTC) of the plant's day that holds ``moment``."""
    return midnight(plant_date(moment, zone), zone)


def day_number(day: date) -> int:
    """Days from 1970-01-01 to ``day`` (the roll-ups' ``day``)."""
    return (day - EPOCH_DATE).days


def plant_days(start: datetime, end: datetime, zone: str, latest: int) -> list[date]:
    """The plant's days that ``[start, end]`` touches, at most the ``latest`` of them."""
    first, last = plant_date(start, zone), plant_date(end, zone)
    first = max(first, step(last, 1 - latest))
    return [step(first, i) for i in range((last - first).days + 1)]


def is_utc(zone: str) -> bool:
    """Whether the plant's days are the UTC days (``UTC`` or a zone always at +00:00)."""
    return zone in ("UTC", "Etc/UTC", "Etc/GMT", "GMT", "Etc/Universal", "Universal", "Zulu")
