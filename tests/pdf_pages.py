"""A PDF's pages as poppler renders them (``pdftoppm``) and their text (``pdftotext``):
Debian's poppler-utils, which CI installs (``.ci/run``); without it these tests skip,
in CI (``CI=true``) they fail. The same for the Noto Sans CJK font a Korean or Chinese
PDF embeds (fonts-noto-cjk, :func:`cjk_font_installed`)."""

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


def page_text(pdf: Path, page: int, *, layout: bool = True) -> str:
    """The text of page ``page`` (from 1), as ``pdftotext`` reads it: laid out as on the
    page, or (``layout`` False) in the order it was written, each table cell's lines
    together."""
    _poppler()
    mode = "-layout" if layout else "-raw"
    result = subprocess.run(
        ["pdftotext", "-f", str(page), "-l", str(page), mode, str(pdf), "-"],
        check=True,
        capture_output=True,
        text=True,
    )
    return result.stdout


def cjk_font_installed(language: str) -> None:
    """Skip (fail in CI) when fontconfig finds no Noto Sans CJK face for ``language``."""
    from station.report.pdf import FontMissingError, cjk_font

    try:
        cjk_font(language)
    except FontMissingError as exc:
        if os.environ.get("CI") == "true":
            pytest.fail(str(exc))
        pytest.skip(str(exc))
