"""The plant's shifts: its days cut at the shifts' start times, in its time zone.

A plant names its shifts by their start times of day in its zone (``06:00,14:00,22:00``,
``CALSTATION_PLANT_SHIFTS``). A shift lasts until the next one starts; the last of a day
runs past midnight to the first of the next day and belongs to the day it started on,
as a night shift does on a line's board. Start times are local wall-clock times, so with
daylight saving time the shift across the change lasts an hour more or less (a start
that falls in the skipped hour begins an hour later, :mod:`zoneinfo`'s ``fold=0``; a
date the zone skipped altogether, as Pacific/Kiritimati did 1994-12-31, has no shifts).

At the ends of the calendar (:mod:`station.domain.quality.days`) the shifts are clamped:
a start whose instant would lie outside the years 1…9999 is the range's end on its side
(a shift that would lie wholly outside has no length and is left out); the moments before
the first date's first start belong to the night shift of the day before it, kept on the
first date (named after the last start, starting at :data:`~station.domain.quality.days.FIRST`);
the last date's last shift ends at :data:`~station.domain.quality.days.LAST`.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import date, datetime, time
from itertools import pairwise
from zoneinfo import ZoneInfo

from station.domain.errors import InputError
from station.domain.quality.days import FIRST, LAST, day_start, plant_date, step, utc

#: The most shifts a day may be cut into (a start every hour).
MAX_SHIFTS = 24


@dataclass(frozen=True)
class Shift:
    """One shift: the plant ``day`` it started on, its ``name`` (start time, ``HH:MM``),
    and its span ``[start, end)`` in UTC."""

    day: date
    name: str
    start: datetime
    end: datetime


def parse_shifts(text: str) -> tuple[time, ...]:
    """``"06:00,14:00,22:00"`` as start times, earliest first; ``""`` for none.

    Raises :class:`InputError` naming the entry that is not an ``HH:MM`` time, a start
    given twice, or more than :data:`MAX_SHIFTS`.
    """
    entries = [entry.strip() for entry in text.split(",") if entry.strip()]
    starts: list[time] = []
    for entry in entries:
        try:
            start = time.fromisoformat(entry)
        except ValueError:
            raise InputError(
                f"shift start {entry!r} is not a time of day (HH:MM, e.g. 06:00,14:00,22:00)"
            ) from None
        if start.tzinfo is not None or start.second or start.microsecond:
            raise InputError(f"shift start {entry!r}: give hours and minutes only (HH:MM)")
        if start in starts:
            raise InputError(f"shift start {entry!r} is given twice")
        starts.append(start)
    if len(starts) > MAX_SHIFTS:
        raise InputError(f"{len(starts)} shift starts: at most {MAX_SHIFTS} a day")
    return tuple(sorted(starts))


def shift_name(start: time) -> str:
    """A shift's name: its start time, ``HH:MM``."""
    return start.strftime("%H:%M")


def plant_shifts(
    start: datetime, end: datetime, zone: str, starts: Sequence[time], latest: int
) -> list[Shift]:
    """The shifts that ``[start, end]`` touches (the latest ``latest`` of them), oldest
    first; none without ``starts``."""
    if not starts:
        return []
    local = ZoneInfo(zone)
    first = step(plant_date(start, zone), -1)  # its night shift
    last = step(plant_date(end, zone), 1)
    moments = [
        (day, shift_name(at), begin)
        for day in (step(first, i) for i in range((last - first).days + 1))
        for at in starts
        for begin in [utc(datetime.combine(day, at, tzinfo=local))]
        if plant_date(begin, zone) == day  # not on a date the zone skipped
    ]
    if first == date.min:  # the night shift of the day before the first date
        moments.insert(0, (first, shift_name(starts[-1]), FIRST))
    if last == date.max:  # the end of the last date's last shift
        moments.append((last, "", LAST))
    shifts = [
        Shift(day=day, name=name, start=begin, end=following)
        for (day, name, begin), (_, _, following) in pairwise(moments)
        if begin < following and following > start and begin <= end
    ]
    return shifts[-latest:]


def shift_start(moment: datetime, zone: str, starts: Sequence[time]) -> datetime:
    """When the shift that holds ``moment`` started (UTC): the plant's shift of ``starts``
    in ``zone``, or, for a plant without shifts, its day (local midnight), the period
    a certificate's golden-unit check is looked for in (``docs/report.md``)."""
    if starts:
        return plant_shifts(moment, moment, zone, starts, 1)[0].start
    return day_start(moment, zone)
