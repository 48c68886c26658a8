"""The CLI's output layer: the only place that writes to the terminal.

``out`` is standard output (results, JSON); ``err`` is standard error (screens,
progress and error lines), so ``--json`` output stays machine-readable.
"""

import json
from typing import Any

from rich.console import Console

out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)


def print_json(payload: Any) -> None:
    """Write ``payload`` as JSON on standard output, nothing else."""
    out.file.write(json.dumps(payload, indent=2, allow_nan=False) + "\n")
    out.file.flush()


def fail(message: str) -> None:
    """Write one error line on standard error."""
    err.print(f"calstation: error: {message}", markup=False)
