"""Two products on one line, on a live server: every statistic of coefficients is one
product's, against its own limits profile; a what-if is one product's; a filter, once
chosen, is kept by every link, form and export of the report's pages.

DIXX-A12 (12-bit, ``kxm52-production``) and DIXX-D16 (16-bit, 8192 counts/g,
``dixx-d16-production``) runs are stored side by side, some of each product out of its own
limits, at stations the products share. The expected figures are recomputed here from
the stored rows (raw SQL) with numpy, never by the code under test.
"""

import csv
import io
import math
import os
from datetime import UTC, datetime, timedelta
from html.parser import HTMLParser
from importlib import resources
from typing import Any
from urllib.parse import parse_qs, urlsplit

import httpx
import numpy as np
import pytest
from sqlalchemy import text

from db import Database, RunRepository
from station.domain.product.limits import load_profile
from tests.api.test_page_language import english_phrases
from tests.conftest import CliRunner
from tests.db.records import T0, make_record

A12, D16 = "DIXX-A12", "DIXX-D16"
PROFILES = {
    A12: load_profile(name="kxm52-production"),
    D16: load_profile(name="dixx-d16-production"),
}
#: Each product's nominal offset and sensitivity (counts, counts/g) and its spread.
NOMINAL = {A12: (2048.0, 819.2, 1.0), D16: (32768.0, 8192.0, 10.0)}
#: The stations each product is built at: line1-st2 builds both.
STATIONS = {A12: ("line1-st1", "line1-st2"), D16: ("line1-st2", "line1-st3")}
RANGE = {"from": "2026-11-02T00:00Z", "to": "2026-11-03T00:00Z"}
COEFFICIENTS = [f"{family}_{axis}" for family in ("offset", "sensitivity") for axis in "xyz"]


def _store(database: Database, per_product: int = 14) -> None:
    """``per_product`` runs of each product, interleaved in time, some out of limits (a
    failed verdict, its coefficients kept) and one unit of each retested."""
    rng = np.random.default_rng(42)
    with database.session() as session:
        repository = RunRepository(session)
        minute = 0
        for i in range(per_product):
            for k, part in enumerate((A12, D16)):
                offset0, sensitivity0, scale = NOMINAL[part]
                bounds = PROFILES[part].offset_counts
                offset = offset0 + rng.normal(0, 40 * scale, 3)
                if i % 5 == 3:  # out of its own offset limits
                    offset[0] = bounds.upper + 5 * scale
                sensitivity = sensitivity0 * (1 + rng.normal(0, 0.01, 3))
                out = not all(bounds.lower <= v <= bounds.upper for v in offset)
                serial = f"PT-{k}{i:05d}" if i != per_product - 1 else f"PT-{k}00000"
                failed = {
                    "verdict": "fail",
                    "failures": [{"code": "offset_out_of_range", "message": "out of limits"}],
                }
                repository.submit(
                    make_record(
                        serial=serial,
                        part_number=part,
                        station_id=STATIONS[part][i % 2],
                        lot="L-1" if i % 3 else "L-2",
                        started_at=T0 + timedelta(minutes=minute),
                        offset=tuple(offset.tolist()),
                        sensitivity=tuple(sensitivity.tolist()),
                        limits=PROFILES[part].ref.model_dump(mode="json"),
                        **(failed if out else {}),
                    )
                )
                minute += 3
        session.commit()


def _raw(database: Database) -> list[Any]:
    """Every stored run, oldest first, as the database holds it."""
    columns = ", ".join(COEFFICIENTS)
    with database.session() as session:
        return list(
            session.execute(
                text(
                    "SELECT serial, part_number, station_id, lot, verdict, "
                    f"{columns} FROM runs ORDER BY started_at, id"
                )
            ).all()
        )


def _bounds(part: str, name: str) -> tuple[float, float]:
    profile = PROFILES[part]
    family = (
        profile.offset_counts if name.startswith("offset") else profile.sensitivity_counts_per_g
    )
    return float(family.lower), float(family.upper)


def _expected_cpk(values: np.ndarray, lower: float, upper: float) -> float:
    mean, sd = float(values.mean()), float(values.std(ddof=1))
    return min(upper - mean, mean - lower) / (3 * sd)


def test_an_unfiltered_report_has_a_section_per_product_from_its_own_runs(
    client: httpx.Client, database: Database
) -> None:
    _store(database)
    raw = _raw(database)
    report = client.get("/api/v1/reports/eol", params=RANGE).json()
    # Never one statistic over two products: the line has counts, the products statistics.
    assert report["parameters"] == []
    assert report["control_charts"] == []
    assert report["near_limits"] is None
    assert report["trend"]
    assert all(cpk is None for day in report["trend"] for cpk in day["cpk"].values())
    assert report["summary"]["runs"] == len(raw)
    sections = {s["part_number"]: s for s in report["product_sections"]}
    assert sorted(sections) == [A12, D16]
    for part, section in sections.items():
        own = [row for row in raw if row.part_number == part]
        assert section["filter"]["part_number"] == part
        assert [ref["sha256"] for ref in section["limits_profiles"]] == [PROFILES[part].ref.sha256]
        stats = {p["name"]: p for p in section["parameters"]}
        charts = {c["name"]: c for c in section["control_charts"]}
        for name in COEFFICIENTS:
            values = np.array([getattr(row, name) for row in own], dtype=float)
            lower, upper = _bounds(part, name)
            p = stats[name]
            assert (p["lower"], p["upper"]) == (lower, upper)
            assert p["count"] == len(values)
            assert math.isclose(p["mean"], values.mean(), rel_tol=1e-9)
            assert math.isclose(p["cpk"], _expected_cpk(values, lower, upper), rel_tol=1e-6)
            assert p["out_of_limits"] == int(np.sum((values < lower) | (values > upper)))
            mr_bar = float(np.abs(np.diff(values)).mean())
            chart = charts[name]
            assert chart["count"] == len(values)
            assert math.isclose(chart["mean"], values.mean(), rel_tol=1e-9)
            assert math.isclose(chart["mr_bar"], mr_bar, rel_tol=1e-9)
            assert math.isclose(chart["ucl"], values.mean() + 3 * mr_bar / 1.128, rel_tol=1e-3)
            assert [pt["serial"] for pt in chart["points"]] == [row.serial for row in own]
        # Each product has runs out of its own limits, and only those count as out.
        assert stats["offset_x"]["out_of_limits"] > 0
        # The same figures as the report filtered to the product.
        alone = client.get("/api/v1/reports/eol", params={**RANGE, "part_number": part}).json()
        assert alone["product_sections"] == []
        assert alone["parameters"] == section["parameters"]
        assert alone["control_charts"] == section["control_charts"]
        assert alone["near_limits"] == section["near_limits"]

    page = client.get("/api/v1/reports/eol", params={**RANGE, "format": "html"}).text
    for part in (A12, D16):
        block = page.split(f'<section class="product" id="product-{part}">', 1)[1]
        block = block.split("</section>", 1)[0]
        assert block.count("<svg") >= len(COEFFICIENTS)  # its histograms and charts
        assert '<table class="parameters">' in block
        assert 'class="what-if filters"' in block
    rows = list(
        csv.reader(
            io.StringIO(client.get("/api/v1/reports/eol", params={**RANGE, "format": "csv"}).text)
        )
    )
    cpk = {(r[1], r[2]): r[3] for r in rows if r[0] == "parameter"}
    for part, section in sections.items():
        for p in section["parameters"]:
            assert cpk[f"{part}/{p['name']}", "cpk"] == ("" if p["cpk"] is None else str(p["cpk"]))
    assert not any(r[0] == "parameter" and "/" not in r[1] for r in rows)


def test_the_split_judges_each_station_against_its_own_products_limits(
    client: httpx.Client, database: Database
) -> None:
    _store(database)
    raw = _raw(database)
    params = {**RANGE, "parameter": "offset_x", "by": "station", "format": "json"}
    split = client.get("/api/v1/reports/split", params=params).json()
    assert split["groups"] == []
    sections = {s["part_number"]: s for s in split["sections"]}
    assert sorted(sections) == [A12, D16]
    for part, section in sections.items():
        lower, upper = _bounds(part, "offset_x")
        assert (section["lower"], section["upper"]) == (lower, upper)
        groups = {g["group"]: g for g in section["groups"]}
        assert sorted(groups) == sorted(STATIONS[part])
        for station, group in groups.items():
            values = np.array(
                [r.offset_x for r in raw if r.part_number == part and r.station_id == station]
            )
            assert group["n"] == len(values)
            assert math.isclose(group["cpk"], _expected_cpk(values, lower, upper), rel_tol=1e-9)
    page = client.get("/api/v1/reports/split", params={**params, "format": "html"}).text
    assert page.count('<section class="product"') == 2


def _profiles(database: Database) -> int:
    """The limits profiles stored."""
    with database.session() as session:
        return int(session.execute(text("SELECT count(*) FROM limits_profiles")).scalar_one())


def _candidate(upper: float) -> bytes:
    """The shipped limits file with kxm52-production's offsets' upper limit at ``upper``."""
    shipped = "offset_counts = { lower = 1841.0, upper = 2255.0 }"
    limits = resources.files("station.domain.profiles").joinpath("limits.toml")
    content = limits.read_text("utf-8")
    assert shipped in content
    changed = content.replace(shipped, f"offset_counts = {{ lower = 1841.0, upper = {upper} }}", 1)
    return changed.encode()


def test_a_what_if_is_one_products(
    client: httpx.Client, database: Database, call_cli: CliRunner, database_url: str, tmp_path: Any
) -> None:
    _store(database)
    raw = _raw(database)
    upload = {"limits": ("candidate.toml", _candidate(2080.0))}
    which = {"profile": "kxm52-production"}
    stored = _profiles(database)
    refused = client.post(
        "/api/v1/reports/eol", params={**RANGE, "format": "json"}, files=upload, data=which
    )
    assert refused.status_code == 422
    error = refused.json()["errors"][0]
    assert error["loc"] == "query.part_number"
    assert A12 in error["msg"]
    assert D16 in error["msg"]
    assert "\n" not in error["msg"]
    page = client.post("/api/v1/reports/eol", params=RANGE, files=upload, data=which)
    assert page.status_code == 422
    assert 'id="problem"' in page.text
    assert _profiles(database) == stored  # a refused candidate is not kept

    a12 = [r for r in raw if r.part_number == A12]
    answer = client.post(
        "/api/v1/reports/eol",
        params={**RANGE, "part_number": A12, "format": "json"},
        files=upload,
        data=which,
    )
    assert answer.status_code == 200, answer.text
    what_if = answer.json()["what_if"]
    assert what_if["summary"]["runs"] == len(a12)
    # Re-judged: the A12 runs that passed with an offset above the candidate's 2080.
    expected = sum(
        r.verdict == "pass" and max(r.offset_x, r.offset_y, r.offset_z) > 2080.0 for r in a12
    )
    assert expected
    assert what_if["pass_to_fail"] == expected
    # The stored what-if answered again by its link: refused over both products too.
    sha = what_if["limits"]["sha256"]
    again = client.get("/api/v1/reports/eol", params={**RANGE, "what_if": sha})
    assert again.status_code == 422

    limits = tmp_path / "candidate.toml"
    limits.write_bytes(_candidate(2080.0))
    env = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    cli = ("report", "--from", RANGE["from"], "--to", RANGE["to"], "--limits", str(limits))
    result = call_cli(*cli, "--database-url", database_url, env=env)
    assert result.returncode == 2
    assert "one product's" in result.stderr
    assert "Traceback" not in result.stderr
    one = call_cli(*cli, "--part-number", A12, "--database-url", database_url, env=env)
    assert one.returncode == 0, one.stderr
    text = call_cli(*cli[:5], "--database-url", database_url, env=env)
    assert text.returncode == 0, text.stderr
    for part in (A12, D16):
        assert f"Parameters of product {part} against limits profile" in text.stdout
        assert f"Control charts of product {part}" in text.stdout


class _Links(HTMLParser):
    """Every address a page offers: links (``href``, and the charts' ``data-href``),
    forms (their action; a GET form's query is its fields)."""

    def __init__(self) -> None:
        super().__init__()
        self.links: list[tuple[str, str]] = []  # (what, address)
        self.forms: list[dict[str, Any]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {name: value or "" for name, value in attrs}
        if tag == "a" and "href" in a:
            self.links.append(("a", a["href"]))
        if "data-href" in a:
            self.links.append(("data-href", a["data-href"]))
        if tag == "form":
            self.forms.append(
                {"method": a.get("method", "get"), "action": a["action"], "fields": {}}
            )
        if tag == "input" and self.forms and "name" in a:
            self.forms[-1]["fields"][a["name"]] = a.get("value", "")


#: The pages' addresses that carry the report's filter.
FILTERED_PATHS = (
    "/api/v1/reports/eol",
    "/api/v1/reports/eol/runs.csv",
    "/api/v1/reports/eol/failures",
    "/api/v1/reports/split",
)
#: The one address that clears the filter, on purpose.
CLEAR = "/api/v1/reports/eol?format=html"


def _kept(query: dict[str, str], filter: dict[str, str], where: str) -> None:
    for name, value in filter.items():
        assert query.get(name) == value, f"{where}: {name} lost ({query})"


def _offered(page: str, base: str) -> list[tuple[str, dict[str, str]]]:
    """Every filtered address ``page`` (at ``base``) offers, with its query."""
    parser = _Links()
    parser.feed(page)
    found = []
    for what, address in parser.links:
        split = urlsplit(address)
        path = split.path or base
        if path in FILTERED_PATHS and address != CLEAR:
            query = {k: v[0] for k, v in parse_qs(split.query).items()}
            found.append((f"{what} {address}", query))
    for form in parser.forms:
        split = urlsplit(form["action"])
        path = split.path or base
        if path not in FILTERED_PATHS:
            continue
        query = {k: v[0] for k, v in parse_qs(split.query).items()}
        if form["method"].lower() == "get":
            query = {k: v for k, v in form["fields"].items() if v}
        found.append((f"form {form['action']}", query))
    return found


def test_every_link_form_and_export_keeps_the_filter(
    client: httpx.Client, database: Database
) -> None:
    _store(database)
    raw = _raw(database)
    chosen = {
        "from": "2026-11-02",
        "to": "2026-11-03",
        "part_number": A12,
        "station": "line1-st2",
        "lot": "L-1",
    }
    # The report, its units paged (2 a page), every unit listed.
    report = client.get(
        "/api/v1/reports/eol", params={**chosen, "format": "html", "list": "all", "units": "2"}
    )
    assert report.status_code == 200
    offered = _offered(report.text, "/api/v1/reports/eol")
    kinds = " ".join(where for where, _ in offered)
    for expected in (
        "runs.csv",
        "format=csv",
        "format=json",
        "/failures",
        "/split",
        "points=1000",
        "page=2",
        "form /api/v1/reports/eol",  # the filter form ("Show")
        "form /api/v1/reports/eol?",  # the what-if form
        "data-href",  # the trend's days
    ):
        assert expected in kinds, f"no {expected} among {kinds}"
    for where, query in offered:
        if "data-href" in where:  # a day's bounds are the day's: the rest is kept
            _kept(query, {k: v for k, v in chosen.items() if k not in ("from", "to")}, where)
        else:
            _kept(query, chosen, where)

    # The pages those links open keep it in turn.
    failures = next(q for w, q in offered if "/failures" in w)
    runs_page = client.get("/api/v1/reports/eol/failures", params=failures).text
    for where, query in _offered(runs_page, "/api/v1/reports/eol/failures"):
        _kept(query, chosen, where)
    # ... and list the runs of the filter only.
    failing = [
        r
        for r in raw
        if r.part_number == A12
        and r.station_id == "line1-st2"
        and r.lot == "L-1"
        and r.verdict == "fail"
    ]
    assert failing
    assert runs_page.count('<a class="serial"') == len(failing)
    split = next(q for w, q in offered if "/split" in w)
    split_page = client.get("/api/v1/reports/split", params=split).text
    split_links = _offered(split_page, "/api/v1/reports/split")
    assert split_links
    for where, query in split_links:
        _kept(query, chosen, where)

    # runs.csv: the filter's runs only, with their part number.
    export = next(q for w, q in offered if "runs.csv" in w)
    rows = list(
        csv.DictReader(io.StringIO(client.get("/api/v1/reports/eol/runs.csv", params=export).text))
    )
    expected = [
        r.serial
        for r in raw
        if r.part_number == A12 and r.station_id == "line1-st2" and r.lot == "L-1"
    ]
    assert [row["serial"] for row in rows] == expected
    assert {row["part_number"] for row in rows} == {A12}
    every = list(
        csv.DictReader(io.StringIO(client.get("/api/v1/reports/eol/runs.csv", params=RANGE).text))
    )
    assert [(row["serial"], row["part_number"]) for row in every] == [
        (r.serial, r.part_number) for r in raw
    ]


@pytest.mark.parametrize("parts", [(A12,), (A12, D16)])
def test_the_dashboard_charts_each_product_apart(
    client: httpx.Client, database: Database, parts: tuple[str, ...]
) -> None:
    now = datetime.now(UTC)
    with database.session() as session:
        repository = RunRepository(session)
        for i in range(6):
            for k, part in enumerate(parts):
                offset0, sensitivity0, _ = NOMINAL[part]
                repository.submit(
                    make_record(
                        serial=f"PT-{k}{i:05d}",
                        part_number=part,
                        started_at=now - timedelta(seconds=30 - 2 * i - k),
                        offset=(offset0 + i, offset0 - i, offset0),
                        sensitivity=(sensitivity0, sensitivity0, sensitivity0 + i),
                        limits=PROFILES[part].ref.model_dump(mode="json"),
                    )
                )
        session.commit()
    page = client.get("/").text
    blocks = page.split('<div class="charts control-charts"')[1:]
    assert len(blocks) == len(parts)
    if len(parts) > 1:
        for part, block in zip(parts, blocks, strict=True):
            assert block.startswith(f' data-part-number="{part}"')
            # Its points are its own product's units, and only theirs.
            serials = {f"PT-{parts.index(part)}{i:05d}" for i in range(6)}
            runs = block.split('data-runs="', 1)[1].split('"', 1)[0].split()
            prefix = block.split('data-prefix="', 1)[1].split('"', 1)[0]
            assert {prefix + r for r in runs} == serials


@pytest.mark.parametrize("language", ["ko", "zh"])
def test_the_sections_and_a_what_if_in_the_readers_language(
    client: httpx.Client, database: Database, language: str
) -> None:
    _store(database)
    sections = client.get(
        "/api/v1/reports/eol", params={**RANGE, "format": "html", "list": "all", "lang": language}
    )
    assert sections.text.count('<section class="product"') == 2
    split = client.get(
        "/api/v1/reports/split",
        params={**RANGE, "parameter": "offset_x", "by": "station", "lang": language},
    )
    what_if = client.post(
        "/api/v1/reports/eol",
        params={**RANGE, "part_number": A12, "lang": language},
        files={"limits": ("candidate.toml", _candidate(2080.0))},
        data={"profile": "kxm52-production"},
    )
    assert 'class="flips"' in what_if.text
    for page in (sections, split, what_if):
        assert page.status_code == 200
        left = sorted(set(english_phrases(page.text)))
        assert left == [], (page.url, left)
