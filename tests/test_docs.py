"""The documentation names only what exists: every path of this repository that
``README.md`` and ``docs/`` name, and every test they cite by name."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: A path of this repository, as the documents write it (not inside a URL or another path).
PATH = re.compile(
    r"(?<![\w/.@:-])((?:station|api|db|tests|benchmarks|docs|examples)/[\w./-]*\w)(::\w+)?"
)


def _named(document: Path) -> list[tuple[str, str | None]]:
    return [
        (m.group(1), m.group(2)[2:] if m.group(2) else None)
        for m in PATH.finditer(document.read_text(encoding="utf-8"))
    ]


@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda p: p.name)
def test_every_path_and_test_a_document_names_exists(document: Path) -> None:
    missing = []
    for path, test in _named(document):
        target = ROOT / path
        if not target.exists():
            missing.append(path)
        elif test is not None and f"def {test}(" not in target.read_text(encoding="utf-8"):
            missing.append(f"{path}::{test}")
    assert missing == []


def test_the_documents_name_paths_at_all() -> None:
    assert len(_named(ROOT / "docs" / "station.md")) > 50


#: How a text names the project's work history rather than the product: an issue or a
#: stop by number, a work session, round or package. (An upstream project's issue, such as
#: pyserial's, is a source like any other.)
HISTORY = re.compile(
    r"(?<!pyserial )\bissues? #?\d+|\bstops? \d+\b|\bwork (session|package)s?\b"
    r"|\bsessions? \d+\b|\b(this|next|previous|earlier|first|second|third|fourth"
    r"|fifth|sixth|seventh|eighth|ninth|night|evening|afternoon|late)('s)? rounds?\b",
    re.IGNORECASE,
)
#: Every document, and every source, test and benchmark file (comments and docstrings).
TEXTS = [
    *DOCUMENTS,
    *(
        path
        for folder in ("station", "api", "db", "tests", "benchmarks")
        for path in sorted((ROOT / folder).rglob("*.py"))
        if path != Path(__file__).resolve()
    ),
]


def _history(text: str) -> list[str]:
    return [m.group(0) for m in HISTORY.finditer(text)]


def test_no_document_or_comment_names_the_work_history() -> None:
    named = {
        str(path.relative_to(ROOT)): found
        for path in TEXTS
        if (found := _history(path.read_text(encoding="utf-8")))
    }
    assert named == {}


@pytest.mark.parametrize(
    "text",
    [
        "measured after issue 28",
        "see Issue #17",
        "stop 39's machine",
        "the eighth round (2026-11-27)",
        "as work session 12 left it",
        "a work package of its own",
    ],
)
def test_the_history_check_finds_what_it_looks_for(text: str) -> None:
    assert _history(text) != []


@pytest.mark.parametrize(
    "text",
    [
        "pyserial issue #759",
        "an alert round",
        "the values it rounds",
        "a round trip to the database",
        "each test session works in a schema of its own",
        "a repository on this session",
        "the station stops the run",
    ],
)
def test_the_history_check_leaves_the_product_alone(text: str) -> None:
    assert _history(text) == []
