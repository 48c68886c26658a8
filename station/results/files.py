"""Durable small files: written whole or not at all, even if the power goes.

The content is fsynced before the rename, so a file is never seen half written. The
directory is not fsynced: after a power cut the rename itself may be lost (the
previous version stays), which costs at most the latest update, while each write
stays one fsync (tens of milliseconds on a slow disk, inside the operator's loop).
"""

import errno
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


#: Plain words for the file-system errors a station meets on the line.
_PLAIN = {
    errno.ENOSPC: "the disk is full",
    errno.EDQUOT: "the disk quota is used up",
    errno.EROFS: "the file system is read-only",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.ENOTDIR: "a part of the path is a file, not a directory",
    errno.EISDIR: "it is a directory",
}


def disk_problem(exc: OSError) -> str:
    """What went wrong writing or reading a file, in the operator's words."""
    return _PLAIN.get(exc.errno or 0) or exc.strerror or type(exc).__name__
