"""``calstation certificate``: the station's own certificate of a unit it calibrated,
end to end: a demo station reads each virtual putter's coefficients before it writes its
own, and the certificate states them as found beside what it left; an authorised
signatory's key, signature and its verification, as real processes."""

import json
import os
import sqlite3
import subprocess
from pathlib import Path

import pytest

from db import RunRepository, open_database
from station.domain.record.records import RunRecord
from station.report.certificate import document_number
from station.report.formatting import number
from tests.conftest import CliRunner
from tests.db.records import make_record
from tests.pdf_pages import cjk_font_installed, page_text, rendered_pages
from tests.station.report.test_certificate_influences import U

STATION = """station_id = "line2-st9"
operator_id = "qa-ann"

[laboratory]
name = "Putter Works Calibration Lab"
address = "12 Gangnam-daero, Seoul"
location = "line 2"
customer = "Putter Works Quality"
gravity_m_s2 = 9.79966
traceability = "g from the plant's absolute gravity survey"
"""


def _env(tmp: Path) -> dict[str, str]:
    env = {**os.environ, "CALSTATION_DATA_DIR": str(tmp)}
    for name in ("CALSTATION_DATABASE_URL", "CALSTATION_STATION_ID", "CALSTATION_OPERATOR_ID"):
        env.pop(name, None)
    return env


@pytest.mark.timeout(240)
def test_the_station_s_own_certificate_states_its_lab_and_the_unit_as_found_and_left(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    config = tmp_path / "station.toml"
    config.write_text(STATION)
    args = ("demo", "--units", "1", "--json", "--speed", "20", "--config", str(config))
    result = run_cli(*args, env=_env(tmp_path), timeout=180)
    assert result.returncode == 0, result.stderr
    [unit] = json.loads(result.stdout)
    with sqlite3.connect(tmp_path / "calstation.sqlite3") as db:
        [(stored,)] = db.execute("select as_found from runs").fetchall()
    found = json.loads(stored)
    # The station read what the virtual putter held before it wrote its own: a unit
    # leaves its maker unwritten, holding the nominal zero; no gyros read (not a
    # whole-unit run).
    assert found["accelerometer"]["written"] is False
    assert found["accelerometer"]["offset"] == [2048.0, 2048.0, 2048.0]
    assert found.get("gyro") is None

    out = tmp_path / "certificate.html"
    args = ("certificate", "issue", unit["serial"], "--config", str(config), "--out", str(out))
    result = run_cli(*args, env=_env(tmp_path))
    assert result.returncode == 0, result.stderr
    page = out.read_text()
    assert "Putter Works Calibration Lab" in page
    assert "line 2, station line2-st9" in page
    assert "held its factory defaults (never calibrated)" in page
    as_found = page.split('class="coefficient-state as-found"')[1].split("</table>")[0]
    assert f"<td>{number(2048.0, 8)}</td>" in as_found
    assert 'class="coefficient-state as-left"' in page
    assert "— end of certificate —" in page


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (("PT999999",), "no calibration run of serial 'PT999999'"),
        (("PT000001", "--language", "fr"), "--language 'fr' is not one of en, ko, zh"),
        (("PT000001", "--config", "/nonexistent.toml"), "cannot read the laboratory"),
        (("PT000001", "--format", "pdf"), "--format pdf needs --out FILE"),
        (("PT000001", "--format", "doc"), "--format 'doc' is not one of html, pdf"),
    ],
)
def test_a_certificate_that_cannot_be_issued_is_one_line_and_exit_2(
    run_cli: CliRunner, tmp_path: Path, args: tuple[str, ...], line: str
) -> None:
    result = run_cli("certificate", "issue", *args, env=_env(tmp_path))
    assert result.returncode == 2
    assert line in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def _database_with(tmp_path: Path, *records: RunRecord) -> str:
    """A SQLite results database holding ``records``; its URL."""
    url = f"sqlite:///{tmp_path / 'results.sqlite3'}"
    database = open_database(url)
    try:
        with database.session() as session:
            for record in records:
                RunRepository(session).submit(record)
            session.commit()
    finally:
        database.dispose()
    return url


def test_a_signatory_signs_and_a_changed_digit_or_another_key_is_refused(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    record = make_record(serial="PT000042")
    url = _database_with(tmp_path, record, make_record(serial="PT000043", verdict="fail"))
    db = ("--database-url", url)
    env = _env(tmp_path)
    for name in ("ann", "bob"):
        key = tmp_path / f"{name}.pem"
        made = run_cli("certificate", "signatory", name, "--key-file", str(key), *db, env=env)
        assert made.returncode == 0, made.stderr
        assert key.stat().st_mode & 0o077 == 0  # the signatory's alone
    again = run_cli(
        "certificate", "signatory", "ann", "--key-file", str(tmp_path / "x.pem"), *db, env=env
    )
    assert again.returncode == 2
    assert again.stderr.strip() == "calstation: error: signatory 'ann' is registered already"

    signed = tmp_path / "signed.json"
    sign = ("certificate", "sign", "PT000042", "--by", "ann", *db)
    impostor = run_cli(*sign, "--key-file", str(tmp_path / "bob.pem"), env=env)
    assert impostor.returncode == 2
    assert "bob.pem is not ann's registered key" in impostor.stderr
    result = run_cli(*sign, "--key-file", str(tmp_path / "ann.pem"), "--out", str(signed), env=env)
    assert result.returncode == 0, result.stderr
    number = document_number(record)
    verified = run_cli("certificate", "verify", str(signed), *db, env=env)
    assert verified.returncode == 0, verified.stderr
    assert verified.stdout.startswith(f"{number}: valid, signed by ann at ")

    # One digit of one coefficient changed: the record is not the one signed.
    text = signed.read_text()
    assert '"x": 2081.9' in text
    changed = tmp_path / "changed.json"
    changed.write_text(text.replace('"x": 2081.9', '"x": 2081.8', 1))
    refused = run_cli("certificate", "verify", str(changed), *db, env=env)
    assert refused.returncode == 2
    assert "the record was changed after it was signed" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1
    # The signature claimed for another signatory: it is not bob's.
    document = json.loads(text)
    document["signature"]["signatory"] = "bob"
    other = tmp_path / "other.json"
    other.write_text(json.dumps(document))
    refused = run_cli("certificate", "verify", str(other), *db, env=env)
    assert refused.returncode == 2
    assert f"{number}: the signature is not bob's" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1

    # Signed once; a unit on hold has nothing to certify.
    twice = run_cli(*sign, "--key-file", str(tmp_path / "ann.pem"), env=env)
    assert twice.returncode == 2
    assert f"{number} is signed already, by ann" in twice.stderr
    held = ("certificate", "sign", "PT000043", "--by", "ann", "--key-file")
    on_hold = run_cli(*held, str(tmp_path / "ann.pem"), *db, env=env)
    assert on_hold.returncode == 2
    assert "PT000043 is on hold" in on_hold.stderr
    # The station's own certificate names the signatory and links the verification.
    page = run_cli("certificate", "issue", "PT000042", *db, env=env).stdout
    assert '<td id="authorised-by">ann, authorised signatory; signed ' in page
    assert f'href="/api/v1/runs/{record.run_id}/signature"' in page
    pdf = tmp_path / "PT000042.pdf"
    args = ("certificate", "issue", "PT000042", "--format", "pdf", "--out", str(pdf), *db)
    made = run_cli(*args, env=env)
    assert made.returncode == 0, made.stderr
    pages = rendered_pages(pdf)
    assert f"{number}" in page_text(pdf, 1)
    assert "ann, authorised signatory; signed" in " ".join(page_text(pdf, len(pages)).split())


#: A fontconfig that knows no font: a machine without fonts-noto-cjk, as fc-match sees it.
NO_FONTS = """<?xml version="1.0"?>
<!DOCTYPE fontconfig SYSTEM "fonts.dtd">
<fontconfig><dir>{fonts}</dir><cachedir>{fonts}/cache</cachedir></fontconfig>
"""


@pytest.mark.parametrize(
    ("language", "words"),
    [("ko", ("교정 성적서", "영향 요인", "단순 판정")), ("zh", ("校准证书", "影响量"))],
)
def test_the_pdf_is_issued_in_korean_and_chinese_with_the_cjk_font_embedded(
    run_cli: CliRunner, tmp_path: Path, language: str, words: tuple[str, ...]
) -> None:
    cjk_font_installed(language)
    record = make_record(serial="PT000044", model="nine", uncertainty=U)
    db = ("--database-url", _database_with(tmp_path, record))
    pdf = tmp_path / f"PT000044-{language}.pdf"
    args = ("certificate", "issue", "PT000044", "--format", "pdf", "--language", language)
    made = run_cli(*args, "--out", str(pdf), *db, env=_env(tmp_path))
    assert made.returncode == 0, made.stderr
    pages = rendered_pages(pdf)  # poppler draws every page
    whole = " ".join(page_text(pdf, i) for i in range(1, len(pages) + 1))
    for word in words:
        assert word in whole, word
    assert document_number(record) in page_text(pdf, 1)
    assert "2081.9" in whole  # the values as stored, beside the words
    # The Hangul and Han come from the embedded Noto Sans CJK, the rest from DejaVu Sans.
    fonts = subprocess.run(["pdffonts", str(pdf)], capture_output=True, text=True, check=True)
    assert "NotoSansCJK" in fonts.stdout
    assert "DejaVuSans" in fonts.stdout
    embedded = [line.split()[-5] for line in fonts.stdout.splitlines()[2:]]
    assert embedded
    assert set(embedded) == {"yes"}


def test_a_cjk_pdf_without_the_font_is_one_line_naming_the_package(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    fonts = tmp_path / "fonts"
    fonts.mkdir()
    (fonts / "fonts.conf").write_text(NO_FONTS.format(fonts=fonts))
    db = ("--database-url", _database_with(tmp_path, make_record(serial="PT000045")))
    env = {**_env(tmp_path), "FONTCONFIG_FILE": str(fonts / "fonts.conf")}
    pdf = tmp_path / "PT000045.pdf"
    args = ("certificate", "issue", "PT000045", "--format", "pdf", "--language", "ko")
    refused = run_cli(*args, "--out", str(pdf), *db, env=env)
    assert refused.returncode == 2
    assert refused.stderr.strip() == (
        "calstation: error: a PDF in ko needs the font Noto Sans CJK KR "
        "(Debian: apt-get install fonts-noto-cjk), which fontconfig does not find"
    )
    assert not pdf.exists()
    # The same machine still issues the English PDF: DejaVu Sans is matplotlib's own.
    english = run_cli(*args[:-2], "--out", str(pdf), *db, env=env)
    assert english.returncode == 0, english.stderr
