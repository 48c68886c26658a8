"""The server verifies a certificate's signature: the stored one (the page's verify
link), and a signed file sent to it; a changed digit or another key is a 422 in one line.
The signed certificate as a PDF names its signatory on its last page."""

import json
from datetime import UTC, datetime
from pathlib import Path

import httpx

from db import Database, RunRepository
from db.store.signatures import add_signature, register_signatory
from station.domain.record.signature import load_private_key, new_key, sign
from station.report.certificate import document_number
from tests.db.records import make_record
from tests.pdf_pages import cjk_font_installed, page_text, rendered_pages

ANN_PEM, ANN = new_key()
BOB_PEM, BOB = new_key()


def test_the_server_verifies_a_signed_certificate_and_refuses_a_changed_one(
    database: Database, client: httpx.Client, tmp_path: Path
) -> None:
    record, unsigned = make_record(serial="U8"), make_record(serial="U9")
    number = document_number(record)
    signature = sign(record, number, "ann", load_private_key(ANN_PEM, "ann"), datetime.now(UTC))
    with database.session() as session:
        repository = RunRepository(session)
        repository.submit(record)
        repository.submit(unsigned)
        register_signatory(session, "ann", ANN)
        register_signatory(session, "bob", BOB)
        add_signature(session, record.run_id, signature)
        session.commit()

    page = client.get("/api/v1/units/U8/certificate").text
    assert '<td id="authorised-by">ann, authorised signatory; signed ' in page
    link = f'<a id="verify" href="/api/v1/runs/{record.run_id}/signature">'
    assert link in page
    check = client.get(f"/api/v1/runs/{record.run_id}/signature").json()
    assert check["valid"] is True
    assert check["certificate"] == number
    assert check["signatory"] == "ann"
    assert check["problem"] is None
    assert client.get(f"/api/v1/runs/{unsigned.run_id}/signature").status_code == 404
    assert "not signed" in client.get("/api/v1/units/U9/certificate").text

    pdf = client.get("/api/v1/units/U8/certificate", params={"format": "pdf"})
    assert pdf.headers["content-type"] == "application/pdf"
    path = tmp_path / "U8.pdf"
    path.write_bytes(pdf.content)
    pages = rendered_pages(path)
    last = " ".join(page_text(path, len(pages)).split())
    assert "ann, authorised signatory; signed" in last
    assert f"page {len(pages)} / {len(pages)}" in last
    # The same PDF in the reader's language: Korean, its Hangul from Noto Sans CJK.
    cjk_font_installed("ko")
    korean = client.get("/api/v1/units/U8/certificate", params={"format": "pdf", "lang": "ko"})
    assert korean.headers["content-type"] == "application/pdf"
    path = tmp_path / "U8-ko.pdf"
    path.write_bytes(korean.content)
    pages = rendered_pages(path)
    assert "교정 성적서" in page_text(path, 1)
    assert "ann" in page_text(path, len(pages))

    signed = client.get(f"/api/v1/runs/{record.run_id}/certificate.json").json()
    answer = client.post("/api/v1/certificates/verify", json=signed)
    assert answer.status_code == 200, answer.text
    assert answer.json()["valid"] is True

    changed = json.loads(json.dumps(signed))
    changed["record"]["coefficients"]["offset"]["x"] += 0.1
    refused = client.post("/api/v1/certificates/verify", json=changed)
    assert refused.status_code == 422
    assert "the record was changed after it was signed" in refused.json()["detail"]
    assert "\n" not in refused.json()["detail"]

    other = json.loads(json.dumps(signed))
    other["signature"]["signatory"] = "bob"
    refused = client.post("/api/v1/certificates/verify", json=other)
    assert refused.status_code == 422
    assert f"{number}: the signature is not bob's" in refused.json()["detail"]
    other["signature"]["signatory"] = "eve"
    refused = client.post("/api/v1/certificates/verify", json=other)
    assert refused.status_code == 422
    assert "eve is not a registered signatory" in refused.json()["detail"]
