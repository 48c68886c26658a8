"""The failure report (and certificate) in the reader's language: ``?lang=``, else the
``Accept-Language`` header's first shipped language, else English; the failures rendered
from their stored code and parameters, codes, serials and values as stored."""

import html
import re
from datetime import timedelta

import httpx
from hypothesis import given
from hypothesis import strategies as st

from api.language import preferred
from db import Database, RunRepository
from db.store.signatures import add_signature, register_signatory
from station.domain.gyro import fit_log, paper_truth, simulate_log
from station.domain.i18n import LANGUAGES
from station.domain.product.limits import Bounds, check, load_profile
from station.domain.record.records import GyroFitRecord, HoldReview
from station.domain.record.signature import load_private_key, new_key, sign
from station.report.certificate import document_number
from tests.db.records import T0, make_record
from tests.station.report.test_certificate import FACTORY
from tests.station.report.test_certificate import GYRO_MATRIX as WHOLE_UNIT_GYRO_MATRIX

SERIAL = "PT-000777"
#: The failure as each language explains it, the page's title and its "what failed".
EXPECTED = {
    "ko": ("자세 잡음 x (자세 3) 8.59057 카운트: ≤ 8 벗어남", "불합격 보고서", "불합격 항목"),
    "zh": ("姿态噪声 x （姿态 3） 8.59057 计数：超出 ≤ 8", "不合格报告", "不合格项"),
}
KEPT = {"mg", "ADC"}
#: The key of the signatory who signs the certificate.
SIGNER_PEM, SIGNER = new_key()


def _store(database: Database) -> str:
    """Two failed runs of one unit, both with a stored pose noise failure; its message."""
    profile = load_profile().model_copy(update={"pose_noise_counts": Bounds(upper=8.0)})
    failure = check(profile, "pose_noise", 8.59057, axis="x", pose=2)
    assert failure is not None
    with database.session() as session:
        repository = RunRepository(session)
        for minutes in (0, 5):
            repository.submit(
                make_record(
                    serial=SERIAL,
                    verdict="fail",
                    started_at=T0 + timedelta(minutes=minutes),
                    failures=[failure.model_dump()],
                )
            )
        session.commit()
    return failure.message


def _failures(page: str) -> list[list[str]]:
    """The cells of the "what failed" table's rows."""
    table = re.search(r'<table class="failures">(.*?)</table>', page, re.S)
    assert table is not None
    return [
        [html.unescape(cell) for cell in re.findall(r"<td>(.*?)</td>", row)]
        for row in re.findall(r"<tr>(.*?)</tr>", table.group(1), re.S)[1:]
    ]


def _earlier_reasons(page: str) -> list[str]:
    return [
        html.unescape(cell) for cell in re.findall(r'<td class="reasons">(.*?)</td>', page, re.S)
    ]


def test_the_failure_report_in_korean_and_chinese_by_lang_or_accept_language(
    client: httpx.Client, database: Database
) -> None:
    message = _store(database)
    url = f"/api/v1/units/{SERIAL}/certificate"
    pages = {
        "ko": client.get(url, params={"lang": "ko"}, headers={"Accept-Language": "zh"}).text,
        "zh": client.get(url, headers={"Accept-Language": "fr-FR, zh-CN;q=0.9, ko;q=0.5"}).text,
    }
    for language, page in pages.items():
        explained, title, what_failed = EXPECTED[language]
        assert f'<html lang="{language}">' in page
        assert f"<h1>{title}</h1>" in page
        assert f'<h2 id="what-failed">{what_failed}</h2>' in page
        (row,) = _failures(page)
        assert row[:2] == ["pose_noise", explained]  # the code as stored
        assert row[2] == "8.59057"
        assert not set(re.findall(r"[A-Za-z]{2,}", " ".join(row[1:]))) - KEPT - {"pose_noise"}
        assert _earlier_reasons(page) == [explained]  # the earlier run's failure too
        assert SERIAL in page
        assert message not in page  # the stored English sentence is not the reader's
    english = client.get(url, headers={"Accept-Language": "fr"}).text
    assert '<html lang="en">' in english
    assert "<h1>Failure report</h1>" in english
    assert _failures(english)[0][:2] == ["pose_noise", message]
    refused = client.get(url, params={"lang": "fr"})
    assert refused.status_code == 422
    assert refused.headers["content-type"].startswith("application/")


languages = st.sampled_from([*LANGUAGES, "fr", "de", "ja", "*"])
regions = st.sampled_from(["", "-KR", "-CN", "-TW", "-US", "-Hans"])
weights = st.sampled_from([None, "1", "0.9", "0.5", "0.25", "0.001", "0"])


@given(st.lists(st.tuples(languages, regions, weights), max_size=6))
def test_accept_language_picks_the_most_wanted_shipped_language(
    entries: list[tuple[str, str, str | None]],
) -> None:
    header = ", ".join(
        f"{tag}{region}" + ("" if weight is None else f";q={weight}")
        for tag, region, weight in entries
    )
    wanted = [
        (float(weight or 1), -position, tag)
        for position, (tag, _, weight) in enumerate(entries)
        if tag in LANGUAGES and float(weight or 1) > 0
    ]
    assert preferred(header) == (max(wanted)[2] if wanted else "en")


def test_a_guard_band_refusal_keeps_its_u_through_the_database(
    client: httpx.Client, database: Database
) -> None:
    guarded = load_profile().model_copy(
        update={"offset_counts": Bounds(lower=1900.0, upper=2200.0), "decision_rule": "guarded"}
    )
    failure = check(guarded, "offset", 2199.6, axis="y", uncertainty=0.8)
    assert failure is not None
    with database.session() as session:
        RunRepository(session).submit(
            make_record(serial=SERIAL, verdict="fail", failures=[failure.model_dump()])
        )
        session.commit()
    stored = client.get(f"/api/v1/units/{SERIAL}").json()["latest"]["failures"]
    assert stored[0]["uncertainty"] == 0.8
    page = client.get(f"/api/v1/units/{SERIAL}/certificate", params={"lang": "ko"}).text
    (row,) = _failures(page)
    assert row[1] == (
        "오프셋 y 2199.6 카운트: [1900, 2200] 안에 있으나 한계까지의 거리가 "
        "불확도 U = 0.8 카운트보다 작음 (보호 대역 판정, w = U)"
    )


#: Tokens in Latin letters a page in Korean or Chinese keeps: units, the names of
#: standards and sources it cites, symbols, the program's and the record's formats.
ALLOWED = {
    *("mg", "ppm", "deg", "sha", "SHA", "UTC", "ADC", "JSON", "calstation", "RMS"),
    *("ISO", "IEC", "JCGM", "GUM", "ILAC", "Song", "Tedaldi", "Monte", "Carlo"),
    *("u_c", "K_ii", "K_ij"),
}
#: A whole unit's gyro matrix, with its verification move, as a run records it.
GYRO_MATRIX = {**WHOLE_UNIT_GYRO_MATRIX, "verification_deg": 0.2}
UNCERTAINTY = {
    "k": 2.0,
    "offset": {"x": 0.5, "y": 0.5, "z": 0.6},
    "sensitivity": {"x": 0.4, "y": 0.4, "z": 0.5},
    "gyro_matrix": [[0.000171, 0.000132, 0.000133]] * 3,
}


def _shown(page: str) -> str:
    """The page's body as a reader sees it: its styles and scripts taken out."""
    body = page.split("<body>", 1)[1]
    return re.sub(r"<(style|script)>.*?</\1>", " ", body, flags=re.S)


def _english_words(page: str, stored: set[str]) -> set[str]:
    """The words in Latin letters of the page's body (its text, tags, styles and scripts
    left out) that are neither a stored value of the record (serials, ids, codes, names)
    nor an allowed token."""
    text = html.unescape(re.sub(r"<[^>]+>", " ", _shown(page)))
    for value in sorted(stored, key=len, reverse=True):
        text = text.replace(value, " ")
    return set(re.findall(r"[A-Za-z_]{2,}", text)) - ALLOWED


def test_the_whole_certificate_and_failure_report_in_korean_and_chinese(
    client: httpx.Client, database: Database
) -> None:
    """A passing certificate (nine-parameter model, gyro matrix, uncertainty, guarded
    rule, that shift's golden-unit check, a lab's gyro fit) and a failure report (an
    earlier run, a review) in ko and zh: no word in Latin letters but the record's own
    values and the allowed tokens; the English page has some (the check can fail)."""
    golden = make_record(serial="GU-001", purpose="golden", started_at=T0 - timedelta(minutes=10))
    passed = make_record(
        serial="PT-000778",
        model="nine",
        lot="L-2611",
        gyro_matrix=GYRO_MATRIX,
        uncertainty=UNCERTAINTY,
        decision_rule="guarded",
        as_found={"read_at": T0.isoformat(), "accelerometer": FACTORY},
    )
    signature = sign(
        passed, document_number(passed), "qa-lee", load_private_key(SIGNER_PEM, "k"), T0
    )
    earlier = make_record(serial=SERIAL, verdict="fail", started_at=T0 - timedelta(hours=1))
    failed = make_record(serial=SERIAL, verdict="fail")
    with database.session() as session:
        repository = RunRepository(session)
        for run in (golden, passed, earlier, failed):
            repository.submit(run)
        repository.add_gyro_fit(
            GyroFitRecord(
                serial=passed.serial,
                fitted_at=T0 - timedelta(days=1),
                source="centrifuge.csv",
                report=fit_log(simulate_log(paper_truth(), seed=3)[0]),
            )
        )
        repository.add_review(
            HoldReview(
                serial=SERIAL,
                run_id=failed.run_id,
                reviewed_at=T0 + timedelta(hours=1),
                reviewer="qe-3",
                root_cause="PCB-7",
                repair_action="R-12",
                decision="retest",
            )
        )
        register_signatory(session, "qa-lee", SIGNER)
        add_signature(session, passed.run_id, signature)
        session.commit()
    stored = {
        value
        for run in (golden, passed, earlier, failed)
        for value in (
            str(run.run_id),
            str(run.run_id)[:8],  # a review names its run so
            document_number(run),
            run.serial,
            run.part_number or "",
            run.station_id,
            run.operator_id,
            run.software_version,
            run.algorithm,
            run.model,
            run.limits.name,
            run.limits.sha256,
            *(f.code for f in run.failures),
            *(p.name for p in run.poses),
        )
        if value
    } | {"qe-3", "PCB-7", "R-12", "centrifuge.csv"}  # a reviewer's words, a lab's file
    # The signatory's name, the signature's and the record's hex digits, the algorithm's
    # name and the command that verifies it, as they are.
    stored |= {"qa-lee", signature.signature[:16], signature.record_sha256, "Ed25519"}
    stored |= {"calstation certificate verify FILE"}
    for run in (passed, failed):
        url = f"/api/v1/units/{run.serial}/certificate"
        english = client.get(url).text
        assert _english_words(english, stored)  # the English page has English words
        for language in ("ko", "zh"):
            page = client.get(url, params={"lang": language}).text
            assert f'<html lang="{language}">' in page
            assert _english_words(page, stored) == set(), (run.verdict, language)
            assert run.serial in page
            assert str(run.run_id) in page
            assert ("centrifuge.csv" in page) == (run is passed)  # the lab's gyro fit's
            assert "GU-001" in page  # that shift's golden-unit check, the reference
            assert ("qa-lee" in page) == (run is passed)  # its authorised signatory
            assert "{" not in _shown(page)  # placeholders filled
