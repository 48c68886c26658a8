"""The commands the documents show do what the documents say: each ``$ calstation ...``
of a code block in ``README.md`` and ``docs/`` that runs offline is run as a real process,
in the order shown, in a fresh directory with a fresh data directory (its embedded
database), and must end
as shown: exit status 2 where the document shows ``calstation: error:``, else 0, and
each line the document shows after it begins as a line the command printed."""

import os
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

from station.results.storage import DatabaseStore
from tests.conftest import CliRunner
from tests.db.records import make_record

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)
#: ``[--option VALUE]``: an option the document marks as optional, left out.
OPTIONAL = re.compile(r"\s\[[^\]]*\]")
#: Commands that serve until stopped (no exit to check).
SERVING = ("serve",)


@dataclass(frozen=True)
class Shown:
    """A command a document shows, and the lines it shows after it."""

    document: str
    argv: tuple[str, ...]
    output: tuple[str, ...]

    @property
    def refused(self) -> bool:
        return any(line.startswith("calstation: error:") for line in self.output)


def _blocks(document: Path) -> list[list[Shown]]:
    """The ``calstation`` commands of each code block of ``document``, in order."""
    blocks = []
    for match in BLOCK.finditer(document.read_text(encoding="utf-8")):
        lines = match.group(2).splitlines()
        shown: list[Shown] = []
        i = 0
        while i < len(lines):
            line = lines[i].strip()
            i += 1
            if not line.startswith("$ calstation "):
                continue
            command = line[2:]
            while command.endswith("\\") and i < len(lines):
                command = command[:-1] + " " + lines[i].strip()
                i += 1
            output = []
            while i < len(lines) and not lines[i].startswith("$ "):
                output.append(lines[i].strip())
                i += 1
            argv = tuple(shlex.split(OPTIONAL.sub("", command), comments=True))
            shown.append(Shown(document.name, argv[1:], tuple(filter(None, output))))
        if shown:
            blocks.append(shown)
    return blocks


BLOCKS = [block for document in DOCUMENTS for block in _blocks(document)]


#: Where a document's example leaves out what differs from run to run (a key, a run id).
ELIDED = re.compile(r"\.\.\.|…|\*\*\*")
#: What ends the letters a word begins with (``csk`` of ``csk_Vq9c...``).
NOT_A_LETTER = re.compile(r"[\W\d_]")


def _first_word(line: str) -> str:
    """The first word of ``line``; of a word with an elided part, the letters it begins
    with (the rest differs from run to run)."""
    word = line.split()[0] if line.split() else ""
    return NOT_A_LETTER.split(word)[0] if ELIDED.search(word) else word


def _begins(shown: str, said: set[str]) -> bool:
    return any(word.startswith(shown) for word in said)


def _stored(data_dir: Path, serial: str, **outcome: str) -> None:
    """A run of ``serial`` in the station's embedded database: a unit sent to rework is
    what a review needs, a calibrated one what a certificate's signing needs."""
    record = make_record(serial=serial, **outcome)
    with DatabaseStore(f"sqlite:///{data_dir / 'calstation.sqlite3'}") as store:
        store.submit(record)


def test_the_documents_show_commands_to_run() -> None:
    commands = [shown.argv[:2] for block in BLOCKS for shown in block]
    assert ("db", "upgrade") in commands
    assert ("demo", "--units") in commands
    assert len(commands) >= 8


@pytest.mark.parametrize(
    "block", BLOCKS, ids=lambda b: f"{b[0].document}:{' '.join(b[0].argv[:2])}"
)
def test_each_command_a_document_shows_ends_as_it_says(
    run_cli: CliRunner, tmp_path: Path, block: list[Shown]
) -> None:
    data_dir = tmp_path / "data"
    env = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    env["CALSTATION_DATA_DIR"] = str(data_dir)
    for shown in block:
        if shown.argv[0] in SERVING:
            continue
        if shown.argv[0] == "review":
            _stored(data_dir, shown.argv[1], verdict="fail", disposition="rework")
        if shown.argv[:2] == ("certificate", "sign"):
            _stored(data_dir, shown.argv[2])
        result = run_cli(*shown.argv, env=env, timeout=600, cwd=tmp_path)
        said = [line.strip() for line in (result.stdout + result.stderr).splitlines()]
        assert result.returncode == (2 if shown.refused else 0), (shown.argv, result.stderr)
        starts = {line.split()[0] for line in said if line.split()}
        shown_words = [_first_word(line) for line in shown.output if not line.startswith("…")]
        missing = [word for word in shown_words if not _begins(word, starts)]
        assert missing == [], (shown.argv, said)
