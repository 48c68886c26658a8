"""A PDF's pages as poppler renders them (``pdftoppm``) and their text (``pdftotext``):
Debian's poppler-utils, which CI installs (``.ci/run``); without it these tests skip,
in CI (``CI=true``) they fail."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest


def _poppler() -> None:
    if shutil.which("pdftoppm") is None or shutil.which("pdftotext") is None:
        if os.environ.get("CI") == "true":
            pytest.fail("pdftoppm is not installed (apt-get install poppler-utils)")
        pytest.skip("pdftoppm is not installed (apt-get install poppler-utils)")


def rendered_pages(pdf: Path) -> list[Path]:
    """The PDF's pages rendered by ``pdftoppm`` as PNG files beside it, in order."""
    _poppler()
    prefix = pdf.with_suffix("")
    subprocess.run(["pdftoppm", "-r", "40", "-png", str(pdf), str(prefix)], check=True)
    pages = sorted(
        pdf.parent.glob(f"{prefix.name}-*.png"), key=lambda p: int(p.stem.rsplit("-")[-1])
    )
    assert all(p.stat().st_size > 0 for p in pages)
    return pages


def page_text(pdf: Path, page: int) -> str:
    """The text of page ``page`` (from 1), as ``pdftotext`` reads it."""
    _poppler()
    result = subprocess.run(
        ["pdftotext", "-f", str(page), "-l", str(page), "-layout", str(pdf), "-"],
        check=True,
        capture_output=True,
        text=True,
    )
    return result.stdout
