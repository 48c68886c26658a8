"""The calibration certificate (or failure report) as a PDF: the same statements as the
HTML page (:mod:`station.report.certificate`), laid out by fpdf2 on A4 pages, each headed
by the document's title and number and footed by "page x / y" (ISO/IEC 17025:2017
7.8.2.1 a), and ended by its end mark, in the reader's language.

Text is set in DejaVu Sans, the TrueType font matplotlib ships (its ``fonts/ttf``), so
the certificate's symbols (±, °, …, −, ⁻¹, ²) print without a system font. DejaVu Sans
holds no Hangul or Han: a Korean or Chinese PDF embeds Noto Sans CJK (Debian's
``fonts-noto-cjk``, which ``.ci/run`` installs) as the font its Hangul and Han fall back
to, found through fontconfig (``fc-match``, :func:`cjk_font`); without it that PDF is
refused with one line naming the package (:class:`FontMissingError`).
"""

import subprocess
from collections.abc import Sequence
from datetime import datetime
from pathlib import Path
from typing import Final

from station.domain.errors import InputError
from station.domain.i18n import LANGUAGES, Language, Say, speaker
from station.domain.product.laboratory import Laboratory
from station.domain.product.limits import LimitsProfile
from station.domain.record.records import RunSummary, StoredRun
from station.domain.record.signature import Signature
from station.report import formatting
from station.report.certificate import (
    CoefficientState,
    Identity,
    as_found,
    as_left,
    check_rows,
    code_words,
    failure_words,
    identity,
    influences,
)
from station.report.explanations import explanation

#: The languages a PDF certificate is set in: every shipped language.
PDF_LANGUAGES: Final = LANGUAGES
#: The font fontconfig is asked for, by language, for a PDF's Hangul or Han: the Korean
#: and the Simplified Chinese faces of Noto Sans CJK (their glyph shapes for shared Han).
CJK_FAMILIES: Final = {"ko": "Noto Sans CJK KR", "zh": "Noto Sans CJK SC"}
#: Longest wait for ``fc-match`` (it reads fontconfig's cache; a cold one takes a second).
_FC_MATCH_TIMEOUT_S: Final = 30.0

_MARGIN_MM = 15
_LINE_MM = 5


class FontMissingError(InputError):
    """A PDF in a language whose script its fonts cannot write on this machine."""


def _font_path(name: str) -> Path:
    """A DejaVu font as matplotlib ships it (``DejaVuSans``, ``DejaVuSans-Bold``)."""
    import matplotlib

    return Path(matplotlib.get_data_path()) / "fonts" / "ttf" / f"{name}.ttf"


def cjk_font(language: str, *, bold: bool = False) -> tuple[Path, int]:
    """The file and collection index of the Noto Sans CJK face that writes ``language``
    (one of :data:`CJK_FAMILIES`), as fontconfig matches it; :class:`FontMissingError`
    when fontconfig matches another family (it answers its nearest font, not none) or
    cannot be asked."""
    family = CJK_FAMILIES[language]
    pattern = f"{family}:style=Bold" if bold else family
    try:
        answer = subprocess.run(
            ["fc-match", "-f", "%{family}\n%{file}\n%{index}\n", pattern],
            capture_output=True,
            text=True,
            check=True,
            timeout=_FC_MATCH_TIMEOUT_S,
        ).stdout.splitlines()
    except (OSError, subprocess.SubprocessError):
        answer = []
    if len(answer) == 3 and family in answer[0].split(","):
        return Path(answer[1]), int(answer[2])
    raise FontMissingError(
        f"a PDF in {language} needs the font {family} (Debian: apt-get install "
        "fonts-noto-cjk), which fontconfig does not find"
    )


def _n(value: float | None, digits: int = 6) -> str:
    return formatting.number(value, digits)


def certificate_pdf(
    run: StoredRun,
    profile: LimitsProfile | None,
    issued_at: datetime,
    zone: str = "UTC",
    golden: RunSummary | None = None,
    laboratory: Laboratory | None = None,
    signature: Signature | None = None,
    language: Language = "en",
) -> bytes:
    """The PDF of ``run``'s certificate (its failure report when it failed), as
    :func:`station.report.html.certificate_page` states it: identity, method, results
    with U and k, the influences, as found and as left, the limits, the statements, the
    signatory; in ``language`` (Korean and Chinese: :func:`cjk_font`)."""
    from fpdf import FPDF
    from fpdf.enums import XPos, YPos

    cjk = (cjk_font(language), cjk_font(language, bold=True)) if language in CJK_FAMILIES else None
    tr = speaker(language)
    words, said = failure_words(tr), code_words(tr)
    ident = identity(run, golden, tr, laboratory=laboratory, issued_at=issued_at)
    title = words[run.verdict]

    class Document(FPDF):
        def header(self) -> None:
            self.set_font("dejavu", size=8)
            self.cell(0, _LINE_MM, f"{title} {ident.number}", new_x=XPos.LMARGIN, new_y=YPos.NEXT)
            self.ln(2)

        def footer(self) -> None:
            self.set_y(-_MARGIN_MM)
            self.set_font("dejavu", size=8)
            page = f"{tr('page')} {self.page_no()} / {{nb}}"
            self.cell(0, _LINE_MM, page, align="R")

    pdf = Document(format="A4")
    pdf.set_margins(_MARGIN_MM, _MARGIN_MM, _MARGIN_MM)
    pdf.set_auto_page_break(True, margin=_MARGIN_MM + _LINE_MM)
    pdf.add_font("dejavu", fname=str(_font_path("DejaVuSans")))
    pdf.add_font("dejavu", style="B", fname=str(_font_path("DejaVuSans-Bold")))
    if cjk is not None:  # Hangul and Han from Noto Sans CJK, the rest in DejaVu Sans
        for style, (file, index) in zip(("", "B"), cjk, strict=True):
            pdf.add_font("cjk", style=style, fname=str(file), collection_font_number=index)
        pdf.set_fallback_fonts(["cjk"])
    pdf.set_title(f"{title} {ident.number}")
    pdf.add_page()

    def heading(text: str, size: int = 12) -> None:
        pdf.ln(2)
        pdf.set_font("dejavu", size=size)
        pdf.multi_cell(0, _LINE_MM + 1, text, new_x=XPos.LMARGIN, new_y=YPos.NEXT)
        pdf.set_font("dejavu", size=8)

    def paragraph(text: str) -> None:
        pdf.multi_cell(0, _LINE_MM - 1, text, new_x=XPos.LMARGIN, new_y=YPos.NEXT)
        pdf.ln(1)

    def table(
        rows: Sequence[Sequence[str]], widths: Sequence[int] | None = None, headed: bool = True
    ) -> None:
        """``rows`` as a table: the first its heading unless not ``headed``."""
        with pdf.table(
            col_widths=widths,
            text_align="LEFT",
            line_height=_LINE_MM - 1,
            first_row_as_headings=headed,
        ) as grid:
            for row in rows:
                cells = grid.row()
                for value in row:
                    cells.cell(value)
        pdf.ln(1)

    heading(title, 16)
    paragraph(tr("times in {zone} · issued {moment}", zone=zone, moment=_moment(issued_at, zone)))
    if run.verdict == "fail":
        paragraph(words["on_hold"])
    table(_identity_rows(run, ident, zone, said, tr), widths=(1, 3), headed=False)

    heading(tr("Method"))
    table(ident.method, widths=(1, 3), headed=False)

    if run.failures:
        heading(words["what_failed"])
        header = [words[k] for k in ("code", "explanation", "measured", "lower", "upper")]
        rows = [
            [
                f.code,
                f.message if language == "en" else explanation(f, language),
                _n(f.measured),
                _n(f.lower),
                _n(f.upper),
            ]
            for f in run.failures
        ]
        table([header, *rows], widths=(4, 6, 2, 2, 2))

    heading(tr("Coefficients"))
    cal, u = run.coefficients, run.uncertainty
    if cal is None:
        paragraph(tr("No coefficients: the run failed before a calibration was solved."))
    else:
        rows = [[tr("axis"), tr("offset (counts)"), tr("sensitivity (counts/g)")]]
        for i, axis in enumerate("xyz"):
            offset = _n(cal.offset.as_tuple()[i], 8)
            sensitivity = _n(cal.sensitivity.as_tuple()[i], 8)
            if u is not None and u.offset is not None:
                offset += f" ± {_n(u.offset.as_tuple()[i], 3)}"
            if u is not None and u.sensitivity is not None:
                sensitivity += f" ± {_n(u.sensitivity.as_tuple()[i], 3)}"
            rows.append([axis, offset, sensitivity])
        table(rows)
        rows = [[tr("axis"), *([tr("matrix (g per count)")] * 3)]]
        for i, axis in enumerate("xyz"):
            cells = [_n(v, 6) for v in cal.matrix[i]]
            if u is not None and u.matrix is not None:
                cells = [
                    f"{c} ± {_n(s, 2)}" if s > 0 else c
                    for c, s in zip(cells, u.matrix[i], strict=True)
                ]
            rows.append([axis, *cells])
        table(rows)
        paragraph(
            tr(
                "± is the expanded uncertainty U with coverage factor k = {k} (about 95 % "
                "coverage for a normal distribution), evaluated per JCGM 100:2008 (GUM): pose "
                "noise, ADC quantisation, the model's unmodelled cross-axis and the fit's "
                "evidence.",
                k=_n(u.k, 2),
            )
            if u is not None
            else tr("No uncertainty recorded for this run.")
        )
        if u is not None and u.matrix is not None:
            paragraph(
                tr(
                    "± of the matrix: the expanded uncertainty U of each entry of the "
                    "nine-parameter model's matrix (k = {k}), from the fit's covariance.",
                    k=_n(u.k, 2),
                )
            )
    found_influences = influences(run, tr)
    if found_influences:
        heading(tr("Influences"))
        table(found_influences, widths=(1, 3), headed=False)
    if run.gyro is not None:
        heading(tr("Gyro"))
        bias = [_n(v) for v in run.gyro.bias.as_tuple()]
        if u is not None and u.gyro_bias_dps is not None:
            bias = [f"{b} ± {_n(v, 4)}" for b, v in zip(bias, u.gyro_bias_dps, strict=True)]
        table([["", "x", "y", "z"], [tr("bias (deg/s)"), *bias]])
    if run.gyro_matrix is not None:
        heading(tr("Gyro matrix K"))
        k = run.gyro_matrix
        spread = u.gyro_matrix if u is not None and u.gyro_matrix is not None else None
        rows = [[tr("gyro"), "K x", "K y", "K z"]]
        for i, row in enumerate(k.matrix):
            cells = [_n(v) for v in row]
            if spread is not None:
                cells = [f"{c} ± {_n(s, 2)}" for c, s in zip(cells, spread[i], strict=True)]
            rows.append(["xyz"[i], *cells])
        table(rows)
        if spread is not None:
            paragraph(
                tr(
                    "± of K: the expanded uncertainty U of each element with coverage factor "
                    "k = {k}: the fit's standard errors and the moves' geometry (the "
                    "accelerometer calibration's uncertainty carried into the gravity "
                    "directions), JCGM 100:2008.",
                    k=_n(u.k if u is not None else None, 2),
                )
            )

    heading(tr("As found and as left"))
    for name, state, missing in (
        (tr("as found"), as_found(run), tr("not recorded")),
        (
            tr("as left"),
            as_left(run),
            tr("not stated: the run did not end in a verified write-back"),
        ),
    ):
        if state is None:
            paragraph(f"{name}: {missing}")
        else:
            table(_state_rows(name, state, tr))

    heading(tr("Limits"))
    if profile is None:
        paragraph(
            tr(
                "its bounds are not stored on this server (the run's station did not send "
                "its profile)"
            )
        )
    else:
        header = [tr("check"), tr("unit of measure"), words["lower"], words["upper"]]
        rows = [[*header, words["measured"], tr("result"), tr("decision rule")]]
        for c in check_rows(run, profile, tr):
            lower = _n(c.lower) if c.lower is not None else words["none"]
            upper = _n(c.upper) if c.upper is not None else words["none"]
            measured = c.measured or "—"
            rows.append([c.name, c.unit, lower, upper, measured, said[c.result], c.rule])
        table(rows, widths=(3, 2, 2, 2, 4, 2, 4))

    heading(tr("Statements"))
    paragraph(
        tr(
            "The results relate only to the item calibrated. This document shall not be "
            "reproduced except in full without the laboratory's written approval."
        )
    )
    rows = [[tr("authorised by"), _authorised(signature, zone, tr)]]
    if signature is not None:
        over = tr("over the record's SHA-256 {sha256}", sha256=signature.record_sha256)
        rows.append([tr("signature"), f"Ed25519 {signature.signature} {over}"])
        rows.append([tr("signature check"), f"/api/v1/runs/{run.run_id}/signature"])
    table(rows, widths=(1, 3), headed=False)
    pdf.ln(4)
    pdf.set_font("dejavu", size=10)
    end = tr("— end of certificate —") if run.verdict == "pass" else tr("— end of report —")
    pdf.cell(0, _LINE_MM, end, align="C")
    return bytes(pdf.output())


def _moment(value: datetime | None, zone: str) -> str:
    return formatting.moment(value, zone)


def _authorised(signature: Signature | None, zone: str, tr: Say) -> str:
    if signature is None:
        return tr("not signed by an authorised signatory")
    signed = tr("authorised signatory; signed {moment}", moment=_moment(signature.signed_at, zone))
    return f"{signature.signatory}, {signed}"


def _state_rows(name: str, state: CoefficientState, say: Say) -> list[list[str]]:
    """One set of coefficients (as found or as left) as table rows, in ``say``'s language."""
    rows = [
        [name, say("offset (counts)"), say("sensitivity (counts/g)"), say("matrix (g per count)")]
    ]
    for i, axis in enumerate("xyz"):
        matrix = ", ".join(_n(v) for v in state.matrix[i])
        rows.append([axis, _n(state.offset[i], 8), _n(state.sensitivity[i], 8), matrix])
    error = f"{state.error_mg:.3f} mg"
    if not state.written:
        error += f" ({say('factory defaults')})"
    rows.append([say("|g| error"), error, "", ""])
    return rows


def _identity_rows(
    run: StoredRun, ident: Identity, zone: str, said: dict[str, str], say: Say
) -> list[tuple[str, str]]:
    """The identity block's rows, as ``templates/identity.html`` lays them out, in
    ``say``'s language."""
    lab = ident.laboratory
    unset = say("not configured")
    golden = ident.golden
    reference = (
        f"{say('golden-unit check')} {golden.serial} "
        + say(
            "at {moment}, {verdict}",
            moment=_moment(golden.started_at, zone),
            verdict=said.get(golden.verdict, golden.verdict),
        )
        if golden is not None
        else say("no golden-unit check on record for this station that shift")
    )
    gravity = _n(lab.gravity_m_s2, 7) if lab.gravity_m_s2 else unset
    traceability = (
        say(
            "each axis is measured against the local acceleration of gravity g = {g} m/s²",
            g=gravity,
        )
        + "; "
        + (lab.traceability or say("its traceability is not configured"))
    )
    if ident.temperature_range is not None:
        low, high = ident.temperature_range
        conditions = say(
            "temperature {low} … {high} °C (the run's poses; mean {mean} °C): the results hold "
            "in this range",
            low=_n(low, 4),
            high=_n(high, 4),
            mean=_n(ident.temperature_c, 4),
        )
    else:
        conditions = say("temperature not recorded")
    rule = said.get(run.decision_rule or "simple", run.decision_rule or "simple")
    number_name = say("certificate number") if run.verdict == "pass" else say("report number")
    return [
        (number_name, ident.number),
        (say("laboratory"), lab.name or unset),
        (say("address"), lab.address or unset),
        (
            say("performed at"),
            f"{lab.location or lab.address or unset}, "
            + say("station {station}", station=run.station_id),
        ),
        (say("customer"), lab.customer or unset),
        (say("item"), say("smart putter's inertial measurement unit (accelerometer and gyros)")),
        (say("serial"), run.serial),
        (say("part number"), run.part_number),
        (say("verdict"), said.get(run.verdict, run.verdict)),
        (say("run"), str(run.run_id)),
        (
            say("received"),
            _moment(ident.received_at, zone) if ident.received_at else say("not recorded"),
        ),
        (say("condition on receipt"), ident.condition or say("not recorded")),
        (say("calibrated"), f"{_moment(run.started_at, zone)} – {_moment(run.finished_at, zone)}"),
        (say("issued"), _moment(ident.issued_at, zone)),
        (say("station / operator"), f"{run.station_id} / {run.operator_id}"),
        (say("lot"), run.lot or "—"),
        (
            say("software / algorithm / model"),
            f"{run.software_version} / {run.algorithm} / {run.model}",
        ),
        (
            say("limits"),
            f"{run.limits.name} v{run.limits.version}, sha256 {run.limits.sha256}",
        ),
        (say("decision rule"), rule),
        (say("reference"), reference),
        (say("traceability"), traceability),
        (say("conditions"), conditions),
    ]
