"""The certificate as a PDF, rendered by poppler: every page bears the title, the number
and "page x / y" with y its page count, the statements are there and the end mark is on
the last page."""

from pathlib import Path

from station.domain.product.limits import load_profile
from station.report.certificate import document_number
from station.report.pdf import certificate_pdf
from tests.db.records import make_record
from tests.pdf_pages import page_text, rendered_pages
from tests.station.report.test_certificate import GYRO_MATRIX, LAB, _found, _stored

U = {
    "k": 2.0,
    "offset": {"x": 0.11, "y": 0.12, "z": 0.13},
    "sensitivity": {"x": 0.21, "y": 0.22, "z": 0.23},
    "gyro_matrix": [[0.000171, 0.000132, 0.000133]] * 3,
}


def test_the_pdf_has_its_pages_numbered_x_of_y_and_states_the_certificate(
    tmp_path: Path,
) -> None:
    run = _found(make_record(model="nine", gyro_matrix=GYRO_MATRIX, uncertainty=U))
    pdf = tmp_path / "certificate.pdf"
    pdf.write_bytes(certificate_pdf(_stored(run), load_profile(), run.finished_at, laboratory=LAB))
    pages = rendered_pages(pdf)
    assert len(pages) >= 2
    number = document_number(run)
    texts = [page_text(pdf, i) for i in range(1, len(pages) + 1)]
    for i, text in enumerate(texts, start=1):
        assert f"Calibration certificate {number}" in text
        assert f"page {i} / {len(pages)}" in text
    whole = "\n".join(texts)
    for line in (
        "Putter Works Calibration Lab",
        "held its factory defaults (never calibrated)",
        "2081.9 ± 0.11",
        "The results relate only to the item calibrated.",
        "not signed by an authorised signatory",
        "g = 9.79966 m/s²",
    ):
        assert line in " ".join(whole.split()), line
    assert "as found" in whole
    assert "as left" in whole
    assert "— end of certificate —" in texts[-1]
    assert all("— end of certificate —" not in text for text in texts[:-1])


def test_a_failure_report_pdf_ends_as_a_report(tmp_path: Path) -> None:
    run = make_record(verdict="fail")
    pdf = tmp_path / "report.pdf"
    pdf.write_bytes(certificate_pdf(_stored(run), None, run.finished_at))
    pages = rendered_pages(pdf)
    last = page_text(pdf, len(pages))
    assert "— end of report —" in last
    assert f"Failure report {document_number(run)}" in page_text(pdf, 1)
    # What failed: its code (a narrow column may wrap it) and the stored message.
    whole = "".join("".join(page_text(pdf, i) for i in range(1, len(pages) + 1)).split())
    assert "sensitivity_out_of_range" in whole
    assert "sensitivityz820.17counts/gabove819.0" in whole
