"""The certificate shows every influence on its results, in HTML and in PDF alike (one
renderer, :func:`station.report.certificate_document.certificate_document`): what U
holds, the influences the record names as left out of U and why, the poses de-weighted
because disturbed, the temperature range the results hold in, the U of the gyro matrix K
and of the nine-parameter matrix's entries, and the decision rule of each limit with its
guard band. Read back as a reader sees it: the page's text, the PDF through pdftotext."""

import re
from datetime import timedelta
from html import unescape
from pathlib import Path

import pytest

from db.store.certificates import CertificateInputs
from station.domain.product.limits import load_profile
from station.domain.record.records import RunRecord
from station.report.certificate import check_rows
from station.report.certificate_document import CertificateFormat, certificate_document
from tests.db.records import make_record
from tests.pdf_pages import page_text, rendered_pages
from tests.station.report.test_certificate import GYRO_MATRIX, LAB, _stored

#: The U a nine-parameter whole-unit run records: its matrix's entries (upper-triangular,
#: g/count), K's, the verification error's; the gyro bias repeatability left out.
U = {
    "k": 2.0,
    "offset": {"x": 0.11, "y": 0.12, "z": 0.13},
    "sensitivity": {"x": 0.21, "y": 0.22, "z": 0.23},
    "gyro_bias_dps": [0.004, 0.005, 0.006],
    "gyro_matrix": [[0.000171, 0.000132, 0.000133]] * 3,
    "verification_error_mg": 0.91,
    "matrix": [[3.1e-7, 2.4e-7, 2.5e-7], [0.0, 3.2e-7, 2.6e-7], [0.0, 0.0, 3.3e-7]],
    "excluded_influences": ["gyro_bias_repeatability"],
}
PROFILE = load_profile(None, "whole-unit").model_copy(update={"decision_rule": "guarded"})
RULES = {
    "offset": "guarded",
    "sensitivity": "guarded",
    "verification_error": "guarded",
    "gyro_bias": "guarded",
    "gyro_scale": "guarded",
    "gyro_misalignment": "guarded",
    "pose_noise": "simple",
}


def _whole_unit(**overrides: object) -> RunRecord:
    """A guarded whole-unit run whose third pose was knocked while taken (its x spread
    4.5 times the others') and whose poses warmed from 24.1 to 24.7 °C."""
    fields: dict[str, object] = {
        "model": "nine",
        "gyro_matrix": GYRO_MATRIX,
        "uncertainty": U,
        "decision_rule": "guarded",
        "check_rules": RULES,
        "limits": PROFILE.ref.model_dump(mode="json"),
    }
    run = make_record(**{**fields, **overrides})
    poses = [
        p.model_copy(
            update={
                "temperature_c": 24.1 + 0.1 * p.index,
                **({"std": p.std.model_copy(update={"x": 4.95})} if p.index == 2 else {}),
            }
        )
        for p in run.poses
    ]
    return run.model_copy(update={"poses": tuple(poses)})


def _text(run: RunRecord, format: CertificateFormat, tmp_path: Path) -> str:
    """The certificate of ``run`` as a reader reads it, its whitespace collapsed."""
    parts = CertificateInputs(_stored(run), (), PROFILE, None, None, (), None)
    document = certificate_document(
        parts, format, run.finished_at + timedelta(hours=1), "UTC", "en", LAB
    )
    if format == "html":
        text = unescape(re.sub(r"<[^>]+>", " ", document.decode()))
    else:
        pdf = tmp_path / "certificate.pdf"
        pdf.write_bytes(document)
        pages = rendered_pages(pdf)
        text = "\n".join(page_text(pdf, i, layout=False) for i in range(1, len(pages) + 1))
    return " ".join(text.split())


@pytest.mark.parametrize("format", ["html", "pdf"])
def test_the_certificate_shows_every_influence_on_its_results(
    format: CertificateFormat, tmp_path: Path
) -> None:
    text = _text(_whole_unit(), format, tmp_path)
    squeezed = "".join(text.split())  # a PDF's narrow table cells wrap their words

    def said(line: str) -> bool:
        return line in text or "".join(line.split()) in squeezed

    for line in (
        # What U holds, and what it leaves out, and why.
        "pose noise, ADC quantisation, the fit's evidence, the sensor's drift with",
        "gyro bias repeatability",
        "not in U: the product's gyros declare no turn-on to turn-on repeatability",
        # The pose de-weighted because disturbed (4.95 over the median 1.1 counts).
        "disturbed pose 3 (x_up)",
        "its spread was 4.5 times the sensor's noise (above 2)",
        # The temperature range the results hold in.
        "the results hold at 24.1 … 24.7 °C",
        # U of K and of the nine-parameter matrix's entries.
        "± of K: the expanded uncertainty U of each element",
        "0.00017",
        "± 2.4e-07",
        "± of the matrix: the expanded uncertainty U of each entry",
        # The decision rule with its guard band, limit by limit.
        "guarded acceptance with guard band w = U",
        "guarded acceptance, w = U: x 0.11, y 0.12, z 0.13",
        "guarded acceptance, w = U: 0.91",
        "guarded acceptance, w = U: ≤ 0.000171",  # the largest of K_ij's
    ):
        assert said(line), line
    assert said("simple acceptance")  # the pose noise: no U, judged by its value


@pytest.mark.parametrize("format", ["html", "pdf"])
def test_an_unrecorded_temperature_is_named_as_left_out_of_u(
    format: CertificateFormat, tmp_path: Path
) -> None:
    run = _whole_unit(uncertainty={**U, "excluded_influences": ["temperature"]})
    cold = tuple(p.model_copy(update={"temperature_c": None}) for p in run.poses)
    text = _text(run.model_copy(update={"poses": cold}), format, tmp_path)
    squeezed = "".join(text.split())
    for line in (
        "not in U: no temperature was recorded at the poses",
        "not recorded: the results hold at the temperature of the calibration",
    ):
        assert "".join(line.split()) in squeezed, line
    assert "sensor's drift with temperature across the poses" not in text
    assert "gyro bias repeatability" not in text


def test_a_guarded_record_from_before_check_rules_shows_k_judged_simply() -> None:
    # Before K and the verification error carried their U into the verdict, a guarded
    # run judged them by their values: its certificate says so, not what a run would now.
    rules = {c.name: c.rule for c in check_rows(_whole_unit(check_rules=None), PROFILE)}
    assert rules["offset"] == "guarded acceptance, w = U: x 0.11, y 0.12, z 0.13"
    assert rules["gyro bias"].startswith("guarded acceptance, w = U")
    for name in ("verification pose error", "gyro scale error K_ii − 1", "gyro misalignment K_ij"):
        assert rules[name] == "simple acceptance", name
    now = {c.name: c.rule for c in check_rows(_whole_unit(), PROFILE)}
    assert now["verification pose error"] == "guarded acceptance, w = U: 0.91"
