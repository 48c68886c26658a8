"""Durable small files: written whole or not at all, even if the power goes.

The content is fsynced before the rename, so a file is never seen half written. The
directory is not fsynced: after a power cut the rename itself may be lost (the
previous version stays), which costs at most the latest update, while each write
stays one fsync (tens of milliseconds on a slow disk, inside the operator's loop).
"""

import os
import tempfile
from pathlib import Path


def write_atomic(path: Path, text: str) -> None:
    """Replace ``path`` with ``text``: write a temporary file, fsync, rename over."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
