"""Reading the report's time bounds: ISO dates or moments, UTC unless a zone is given.

One place for the CLI (``calstation report --from/--to``) and the API
(``/api/v1/reports/eol?from=&to=``): a bound that names no moment, or one the report
cannot work with, is an :class:`InputError` naming the option.
"""

from datetime import UTC, date, datetime, time

from station.errors import InputError

#: The moments a report bound may name, UTC: the report counts whole days from a bound
#: to the next midnight, which must still be a date (years 1…9999).
MOMENT_MIN = datetime(1, 1, 1, tzinfo=UTC)
MOMENT_MAX = datetime(9999, 12, 31, tzinfo=UTC)

#: The most units a report lists (``--units``, ``units=``): years of a line's output.
MAX_LISTED_UNITS = 1_000_000


def parse_moment(text: str, *, name: str) -> datetime:
    """``2026-11-02`` (midnight UTC), ``2026-11-02T14:00`` (UTC) or with a zone.

    Raises :class:`InputError` naming the option ``name`` for anything else, and for a
    moment outside :data:`MOMENT_MIN` … :data:`MOMENT_MAX` once in UTC.
    """
    try:
        moment = datetime.fromisoformat(text)
    except ValueError:
        try:
            moment = datetime.combine(date.fromisoformat(text), time())
        except ValueError:
            raise InputError(
                f"{name} {text!r} is not an ISO date or time (e.g. 2026-11-02 or 2026-11-02T14:00Z)"
            ) from None
    outside = InputError(
        f"{name} {text!r} is outside {MOMENT_MIN.date()} … {MOMENT_MAX.date()} 00:00 (UTC)"
    )
    try:
        moment = moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)
    except OverflowError:  # the zone shifts it past year 1 or 9999
        raise outside from None
    if not MOMENT_MIN <= moment <= MOMENT_MAX:
        raise outside
    return moment


def check_range(since: datetime | None, until: datetime | None, *, names: str) -> None:
    """Raise :class:`InputError` when the start ``since`` is after the end ``until``
    (``names`` says both options, e.g. ``--from/--to``)."""
    if since is not None and until is not None and since > until:
        start, end = names.split("/")
        first, last = (moment.isoformat(" ", "minutes")[:16] for moment in (since, until))
        raise InputError(f"{start} {first} UTC is after {end} {last}")


def start_of_day(now: datetime) -> datetime:
    """Midnight UTC of the day ``now`` is in."""
    return datetime.combine(now.astimezone(UTC).date(), time(), tzinfo=UTC)
