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
