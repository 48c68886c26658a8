"""How numbers read in the text and HTML renderings (the same in both)."""

from datetime import datetime


def percent(value: float | None) -> str:
    """A fraction as a percentage with one decimal: ``0.875`` → ``87.5 %``."""
    return "–" if value is None else f"{100 * value:.1f} %"


def number(value: float | int | None, digits: int = 4) -> str:
    """``digits`` significant digits (integers in full); ``–`` for no value."""
    if value is None:
        return "–"
    if isinstance(value, int):
        return str(value)
    return f"{value:.{digits}g}"


def seconds(value: float | None) -> str:
    """A duration in seconds with one decimal."""
    return "–" if value is None else f"{value:.1f} s"


def moment(value: datetime | None) -> str:
    """A UTC moment to the second."""
    return "–" if value is None else value.strftime("%Y-%m-%d %H:%M:%S UTC")
