"""A unit's certificate as a document: the HTML page or the PDF of the same statements,
from what the results database holds of it (the server's page and ``calstation
certificate issue`` render it here)."""

from collections.abc import Sequence
from datetime import datetime
from typing import Literal, Protocol

from station.domain.i18n import Language
from station.domain.product.laboratory import Laboratory
from station.domain.product.limits import LimitsProfile
from station.domain.record.records import GyroFitRecord, HoldReview, RunSummary, StoredRun
from station.domain.record.signature import Signature

#: The formats a certificate is rendered in.
CertificateFormat = Literal["html", "pdf"]


class CertificateParts(Protocol):
    """What a certificate states of its unit (``db.store.certificates.CertificateInputs``)."""

    @property
    def run(self) -> StoredRun: ...
    @property
    def earlier(self) -> Sequence[RunSummary]: ...
    @property
    def profile(self) -> LimitsProfile | None: ...
    @property
    def gyro_fit(self) -> GyroFitRecord | None: ...
    @property
    def golden(self) -> RunSummary | None: ...
    @property
    def reviews(self) -> Sequence[HoldReview]: ...
    @property
    def signature(self) -> Signature | None: ...


def certificate_document(
    parts: CertificateParts,
    format: CertificateFormat,
    issued_at: datetime,
    zone: str,
    language: Language,
    laboratory: Laboratory,
) -> bytes:
    """The certificate of ``parts`` as ``format``: the page (UTF-8) or the PDF, in
    ``language`` (a Korean or Chinese PDF needs the Noto Sans CJK font:
    :func:`station.report.pdf.cjk_font`). The renderers are imported here, when one is
    asked for: a PDF's library stays out of a page's process."""
    if format == "pdf":
        from station.report.pdf import certificate_pdf

        return certificate_pdf(
            parts.run,
            parts.profile,
            issued_at,
            zone,
            parts.golden,
            laboratory,
            parts.signature,
            language,
        )
    from station.report.html import certificate_page

    page = certificate_page(
        parts.run,
        parts.profile,
        issued_at,
        parts.gyro_fit,
        parts.earlier,
        zone,
        parts.golden,
        parts.reviews,
        language,
        laboratory,
        parts.signature,
    )
    return page.encode()
