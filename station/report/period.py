"""Reading the report's time bounds: ISO dates or moments, UTC unless a zone is given."""

from datetime import UTC, date, datetime, time

from station.errors import InputError


def parse_moment(text: str, *, name: str) -> datetime:
    """``2026-11-02`` (midnight UTC), ``2026-11-02T14:00`` (UTC) or with a zone.

    Raises :class:`InputError` naming the option ``name`` for anything else.
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
    return moment.replace(tzinfo=UTC) if moment.tzinfo is None else moment.astimezone(UTC)


def start_of_day(now: datetime) -> datetime:
    """Midnight UTC of the day ``now`` is in."""
    return datetime.combine(now.astimezone(UTC).date(), time(), tzinfo=UTC)
