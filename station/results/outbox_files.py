"""One outbox file: read it as a run record, or say in one line why it cannot be read.

A file in the outbox may be torn (power cut while another tool wrote it), empty, binary,
not UTF-8, or a record that no longer validates (the model's bounds grew stricter
since it was written); or no file at all under a record's name: a FIFO, a directory, a
symbolic link, a device. None of these may stop the outbox: it is moved aside, next to
a ``.reason.txt`` naming the problem, and kept for a person to look at (``calstation
outbox``). A path is opened without following a link and without blocking (a FIFO
with no writer would hold the sender and ``outbox list`` forever), and read only when
it is a regular file.
"""

import json
import logging
import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from station.domain.errors import CalstationError
from station.domain.record.records import RunRecord
from station.results.files import write_atomic

log = logging.getLogger(__name__)

REASON_SUFFIX = ".reason.txt"


class UnreadableRecordError(CalstationError):
    """An outbox file that is not a valid run record; the message is the reason."""


#: What a path that is not a regular file is, by its ``st_mode`` type.
_NOT_A_FILE = {
    stat.S_IFIFO: "a FIFO",
    stat.S_IFDIR: "a directory",
    stat.S_IFLNK: "a symbolic link",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
}


def read_bytes(path: Path) -> bytes:
    """The bytes of the regular file ``path``; :class:`UnreadableRecordError` names why
    not (what the path is when it is no regular file). Never blocks, never follows a
    link."""
    kind = _kind(path)
    if kind is not None:
        raise UnreadableRecordError(f"not a record file: {kind}")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOFOLLOW)
    except OSError as exc:
        raise UnreadableRecordError(f"cannot read the file: {exc.strerror or exc}") from None
    with os.fdopen(fd, "rb") as handle:
        kind = _NOT_A_FILE.get(stat.S_IFMT(os.fstat(fd).st_mode))  # replaced meanwhile
        if kind is not None:
            raise UnreadableRecordError(f"not a record file: {kind}")
        try:
            return handle.read()
        except OSError as exc:
            raise UnreadableRecordError(f"cannot read the file: {exc.strerror or exc}") from None


def _kind(path: Path) -> str | None:
    """What ``path`` is when it is no regular file (None: a regular file, or gone)."""
    try:
        mode = path.lstat().st_mode
    except OSError:
        return None
    return _NOT_A_FILE.get(stat.S_IFMT(mode))


def read_record(path: Path) -> RunRecord:
    """The run record in ``path``; :class:`UnreadableRecordError` names why not."""
    data = read_bytes(path)
    if not data.strip():
        raise UnreadableRecordError("empty file")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise UnreadableRecordError(
            f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})"
        ) from None
    try:
        return RunRecord.model_validate_json(text)
    except ValidationError as exc:
        raise UnreadableRecordError(_validation_reason(exc)) from None


def _validation_reason(exc: ValidationError) -> str:
    errors = exc.errors()
    first = errors[0]
    if first["type"] == "json_invalid":
        return f"not JSON (torn or garbled): {first['msg']}"
    where = ".".join(str(part) for part in first["loc"]) or "record"
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    return f"not a valid run record: {where}: {first['msg']}{more}"


@dataclass(frozen=True)
class FileSummary:
    """What can be told about a record file even when it does not validate."""

    run_id: str
    serial: str | None
    verdict: str | None


def summarise(path: Path) -> FileSummary:
    """Run id, serial and verdict of ``path`` as far as its JSON gives them."""
    fields: dict[str, Any] = {}
    try:
        loaded = json.loads(read_bytes(path))
    except (UnreadableRecordError, ValueError):
        loaded = None
    if isinstance(loaded, dict):
        fields = {k: v for k, v in loaded.items() if isinstance(v, str)}
    return FileSummary(fields.get("run_id", path.stem), fields.get("serial"), fields.get("verdict"))


def reason_path(path: Path) -> Path:
    """The ``.reason.txt`` next to a record file set aside."""
    return path.with_name(f"{path.stem}{REASON_SUFFIX}")


def reason_of(path: Path) -> str | None:
    """The reason a record file was set aside (None when it has none)."""
    try:
        return reason_path(path).read_text(encoding="utf-8", errors="replace").strip() or None
    except OSError:
        return None


def set_aside(path: Path, directory: Path, reason: str) -> bool:
    """Move ``path`` into ``directory`` with its one-line reason; False if the disk refused."""
    line = " ".join(reason.split())
    try:
        directory.mkdir(exist_ok=True)
        write_atomic(reason_path(directory / path.name), f"{line}\n")
        path.replace(directory / path.name)
    except OSError as exc:
        log.error("cannot move %s to %s: %s", path.name, directory, exc)
        return False
    return True
