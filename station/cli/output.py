"""The CLI's output layer: the only place that writes to the terminal.

``out`` is standard output (results, JSON); ``err`` is standard error (progress and
error lines), so ``--json`` output stays machine-readable. Both leave a long line whole
(soft wrap: the terminal wraps it, a log keeps it on one line). The operator's screens are
drawn on a :func:`screen_console` instead.
"""

import json
from typing import Any

from rich.console import Console

out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)


def screen_console(**options: Any) -> Console:
    """A console for the operator's screens (``options``: rich's, e.g. ``stderr``): each
    line wrapped between words at the terminal's width, counted in cells (a Hangul or Han
    character takes two), never cut. rich's ``Live`` display crops every line at the edge,
    so a screen drawn on a soft-wrapping console loses the end of each long line."""
    return Console(highlight=False, soft_wrap=False, **options)


def print_json(payload: Any) -> None:
    """Write ``payload`` as JSON on standard output, nothing else."""
    out.file.write(json.dumps(payload, indent=2, allow_nan=False) + "\n")
    out.file.flush()


def fail(message: str) -> None:
    """Write one error line on standard error."""
    err.print(f"calstation: error: {message}", markup=False)
