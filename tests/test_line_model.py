"""The whole line against an oracle: a Hypothesis stateful test of a real server.

Several stations build both products (``tests/datasheet_units.py``: units whose true
offsets and sensitivities are known, from the datasheets alone) and submit their runs to
a real ``calstation serve`` over HTTP: new units passing or failing, retests at any
station, operators' aborts, quality reviews of held units, runs an outbox delivers late
and runs on odd dates (the first moment the server takes, the days daylight saving time
starts and ends in the plant's zone, a leap day, the last year the server takes). After
every step the server's answers must equal the figures ``tests/line_oracle.py``
recomputes from the raw runs: the end-of-line report's JSON unfiltered and filtered by
product, by station and by a plant day, its per-product capability, the units' answers
and reviews, the split by station and by product, and the dashboard's tiles, rows, held
units and control-chart centres.

Floats: counts and yields are ratios of the same integers (compared to 1e-12); means,
standard deviations and Cp/Cpk come from the server's sums about the tolerance centre
(``docs/report.md``, "How it is computed") in another order than the oracle's, so they
are compared within a bound of that arithmetic's rounding (:func:`_same_capability`).

Sizes: ``examples(...)`` runs and steps (``tests/conftest.py``): small in ``make test``,
large under ``HYPOTHESIS_PROFILE=nightly``.
"""

import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from datetime import UTC, date, datetime, time, timedelta
from typing import Any, TypeVar
from zoneinfo import ZoneInfo

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    rule,
    run_state_machine_as_test,
)

from db import Database, RunRepository
from db.base import Base
from station.domain.record.records import RunRecord
from station.results.storage import DatabaseStore
from tests.conftest import NIGHTLY, examples
from tests.datasheet_units import PRODUCTS, Datasheet, Unit, bounds, run_payload
from tests.line_oracle import COEFFICIENTS, Capability, Counts, Line, Run, Selection
from tests.servers import local_client, serving

STATIONS = ("line1-st1", "line1-st2", "line2-st1")
PLANT_ZONE = ZoneInfo("Europe/Berlin")
#: Plant days the report is filtered to: the days daylight saving time starts (23 hours)
#: and ends (25 hours) in the plant's zone.
PLANT_DAYS = (date(2021, 3, 28), date(2021, 10, 31))
#: Late and odd start times: each plant day's first and last moments and a moment either
#: side, the hour that does not exist and the one that happens twice, the first moment the
#: server takes, a leap day, the last year it takes.
ODD_MOMENTS = (
    datetime(2021, 3, 27, 22, 59, 59, tzinfo=UTC),
    datetime(2021, 3, 27, 23, 0, tzinfo=UTC),
    datetime(2021, 3, 28, 1, 30, tzinfo=UTC),
    datetime(2021, 3, 28, 21, 57, tzinfo=UTC),
    datetime(2021, 3, 28, 22, 0, tzinfo=UTC),
    datetime(2021, 10, 30, 22, 0, tzinfo=UTC),
    datetime(2021, 10, 31, 0, 30, tzinfo=UTC),
    datetime(2021, 10, 31, 1, 30, tzinfo=UTC),
    datetime(2021, 10, 31, 22, 57, tzinfo=UTC),
    datetime(2021, 10, 31, 23, 0, tzinfo=UTC),
    datetime(2000, 1, 1, tzinfo=UTC),
    datetime(2024, 2, 29, 23, 0, tzinfo=UTC),
    datetime(2199, 12, 31, 22, 0, tzinfo=UTC),
)
EDGE_YEARS = (datetime(1, 1, 1, tzinfo=UTC), datetime(9999, 12, 31, 22, 0, tzinfo=UTC))
#: Relative tolerance of figures that are ratios of the same integers (one division).
RATIO_TOLERANCE = 1e-12
#: Relative rounding of a sum of a few thousand doubles (n·ε with room to spare).
SUM_ROUNDING = 1e-12
#: Seconds after which the test counts as hung (pytest-timeout; not a speed check: a
#: failing example's shrinking alone may take Hypothesis' five minutes).
HUNG_MACHINE_S = 7200 if NIGHTLY else 1200
RUNS = "/api/v1/runs"
T = TypeVar("T")
REPORT = "/api/v1/reports/eol"
SPLIT = "/api/v1/reports/split"


@pytest.fixture(scope="module")
def line_url(migrated_database: Database, database_url: str) -> Iterator[str]:
    """A server of the session's database whose plant is in :data:`PLANT_ZONE`."""
    with serving(database_url, plant_timezone=PLANT_ZONE.key) as base:
        yield base


@pytest.mark.timeout(HUNG_MACHINE_S)
def test_the_line_answers_what_the_raw_runs_say(line_url: str, database: Database) -> None:
    machine = _machine(line_url, database)
    run_state_machine_as_test(
        machine,
        settings=settings(
            max_examples=examples(40),
            stateful_step_count=40 if NIGHTLY else 6,
            deadline=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
        ),
    )


@dataclass
class ModelUnit:
    """A unit as the line knows it: its truth, and what the station lets happen to it."""

    unit: Unit
    passed_before: bool = False
    attempts_since_review: int = 0
    #: Sent to rework and not yet reviewed: every station refuses its scan.
    blocked: bool = False
    scrapped: bool = False


def _machine(base: str, database: Database) -> type[RuleBasedStateMachine]:
    class LineModel(RuleBasedStateMachine):
        """The line: stations submitting runs, quality reviewing, all checked against
        the oracle after every step."""

        def __init__(self) -> None:
            super().__init__()
            self.http = local_client(base)
            self.line = Line()
            self.units: dict[str, ModelUnit] = {}
            self.reviews: dict[str, list[tuple[str, str]]] = {}
            self.keys: dict[str, str] = {}
            self.quality_key = ""
            self.clock = datetime.now(UTC).replace(microsecond=0) - timedelta(hours=2)
            self.steps = 0

        def teardown(self) -> None:
            self.http.close()

        @initialize()
        def empty_line(self) -> None:
            with database.engine.begin() as connection:
                for table in reversed(Base.metadata.sorted_tables):
                    connection.execute(table.delete())
            with database.session() as session, session.begin():
                repository = RunRepository(session)
                self.keys = {s: repository.create_key(s) for s in STATIONS}
                self.quality_key = repository.create_key("qe-model", "quality")

        # -- the line's events ------------------------------------------------------

        @rule(
            product=st.sampled_from(PRODUCTS),
            station=st.sampled_from(STATIONS),
            data=st.data(),
        )
        def new_unit(self, product: Datasheet, station: str, data: st.DataObject) -> None:
            serial = f"PT{len(self.units) + 1:06d}"
            model = ModelUnit(data.draw(_units(serial, product)))
            self.units[serial] = model
            self._submit(model, station, self._tick())

        @rule(station=st.sampled_from(STATIONS), data=st.data())
        def retest(self, station: str, data: st.DataObject) -> None:
            serial = data.draw(st.sampled_from(self._scannable() or ["-"]))
            if serial == "-":
                return
            model = self.units[serial]
            # Repaired, reworked or as it was: the unit's truth drawn again.
            model.unit = data.draw(_units(serial, model.unit.product))
            self._submit(model, station, self._tick())

        @rule(station=st.sampled_from(STATIONS), fresh=st.booleans(), data=st.data())
        def abort(self, station: str, fresh: bool, data: st.DataObject) -> None:
            scannable = self._scannable()
            if fresh or not scannable:
                serial = f"PT{len(self.units) + 1:06d}"
                product = data.draw(st.sampled_from(PRODUCTS))
                self.units[serial] = ModelUnit(data.draw(_units(serial, product)))
            else:
                serial = data.draw(st.sampled_from(scannable))
            self._submit(self.units[serial], station, self._tick(), aborted=True)

        @rule(decision=st.sampled_from(["retest", "scrap"]), data=st.data())
        def review(self, decision: str, data: st.DataObject) -> None:
            held = [
                s
                for s in sorted(self.units)
                if (history := self.line.history(s))
                and history[-1].attempt
                and not history[-1].passed
                and not self.units[s].scrapped
            ]
            if not held:
                return
            serial = data.draw(st.sampled_from(held))
            latest = self.line.history(serial)[-1]
            answer = self.http.post(
                f"/api/v1/units/{serial}/reviews",
                json={
                    "run_id": latest.run_id,
                    "root_cause": "found by the model",
                    "repair_action": "none" if decision == "scrap" else "reworked",
                    "decision": decision,
                },
                headers={"Authorization": f"Bearer {self.quality_key}"},
            )
            assert answer.status_code == 201, answer.text
            self.reviews.setdefault(serial, []).append((latest.run_id, decision))
            model = self.units[serial]
            model.scrapped = decision == "scrap"
            model.blocked = False
            model.attempts_since_review = 0

        @rule(
            station=st.sampled_from(STATIONS),
            when=st.sampled_from(ODD_MOMENTS),
            fresh=st.booleans(),
            data=st.data(),
        )
        def late_run(self, station: str, when: datetime, fresh: bool, data: st.DataObject) -> None:
            """A run an outbox delivers late, or one on an odd date: of a new unit or of
            one already known (it slots into the unit's history by its start)."""
            started = when + timedelta(seconds=len(self.line.runs))  # distinct starts
            if fresh or not self.units:
                serial = f"PT{len(self.units) + 1:06d}"
                product = data.draw(st.sampled_from(PRODUCTS))
                self.units[serial] = ModelUnit(data.draw(_units(serial, product)))
            else:
                serial = data.draw(st.sampled_from(sorted(self.units)))
            self._submit(self.units[serial], station, started)

        @rule(station=st.sampled_from(STATIONS), when=st.sampled_from(EDGE_YEARS), data=st.data())
        def run_in_an_edge_year(self, station: str, when: datetime, data: st.DataObject) -> None:
            """A run stamped in the year 1 or 9999 by a station's clock gone wrong, stored
            through the station's own database (the results server takes only
            2000…2199)."""
            serial = f"PT{len(self.units) + 1:06d}"
            product = data.draw(st.sampled_from(PRODUCTS))
            model = self.units[serial] = ModelUnit(data.draw(_units(serial, product)))
            payload = run_payload(model.unit, station_id=station, started_at=when, seconds=60)
            DatabaseStore(database=database).submit(RunRecord.model_validate(payload))
            self.line.add(Run.of_payload(payload))

        # -- invariants ------------------------------------------------------------------

        @invariant()
        def the_report_counts_what_the_runs_say(self) -> None:
            self.steps += 1
            report = self._report()
            self._same_summary(report["summary"], self.line.counts(), "summary")
            self._same_rows(report["stations"], "station_id", self.line.stations(), "stations")
            self._same_rows(report["products"], "part_number", self.line.products(), "products")
            open_holds = self._open_holds()
            assert report["open_holds"]["total"] == open_holds, ("open_holds", report["open_holds"])
            # Never one statistic over two products: a capability figure of the line is
            # one product's (a section per product is wp-products' work).
            for stats in report["parameters"]:
                if stats["name"] in COEFFICIENTS and stats["count"]:
                    assert any(
                        stats["count"]
                        == len(self.line.values(stats["name"], Selection(p.part_number)))
                        and _close(stats["mean"], self._capability(stats["name"], p).mean)
                        for p in PRODUCTS
                    ), ("a statistic over two products", stats["name"], _brief(stats))
            # Over two products, a section a product: its runs against its own limits.
            sections = {s["part_number"]: s for s in report["product_sections"]}
            with_values = {
                p.part_number
                for p in PRODUCTS
                if self.line.values(COEFFICIENTS[0], Selection(p.part_number))
            }
            if len(self.line.products()) > 1:
                assert with_values <= set(sections), ("product sections", sorted(sections))
            for product in PRODUCTS:
                if product.part_number not in sections:
                    continue
                where = f"unfiltered report, section {product.part_number}"
                stats = {p["name"]: p for p in sections[product.part_number]["parameters"]}
                for name in COEFFICIENTS:
                    expected = self._capability(name, product)
                    if expected.count:
                        _same_capability(stats[name], expected, product, name, where)

        @invariant()
        def each_products_report_holds_its_runs_and_its_limits(self) -> None:
            for product in self._in_turn(PRODUCTS):
                selection = Selection(part_number=product.part_number)
                report = self._report(part_number=product.part_number)
                where = f"report part_number={product.part_number}"
                self._same_summary(report["summary"], self.line.counts(selection), where)
                self._same_rows(
                    report["stations"], "station_id", self.line.stations(selection), where
                )
                stats = {p["name"]: p for p in report["parameters"]}
                for name in COEFFICIENTS:
                    expected = self._capability(name, product)
                    if expected.count:
                        _same_capability(stats[name], expected, product, name, where)

        @invariant()
        def each_stations_report_holds_its_runs(self) -> None:
            for station in self._in_turn(sorted({r.station_id for r in self.line.runs})):
                selection = Selection(station_id=station)
                report = self._report(station=station)
                where = f"report station={station}"
                self._same_summary(report["summary"], self.line.counts(selection), where)
                self._same_rows(
                    report["stations"], "station_id", self.line.stations(selection), where
                )
                self._same_rows(
                    report["products"], "part_number", self.line.products(selection), where
                )

        @invariant()
        def a_plant_days_report_holds_that_days_runs(self) -> None:
            for day in self._in_turn(PLANT_DAYS):
                next_day = (day + timedelta(days=1)).isoformat()
                report = self._report(**{"from": day.isoformat(), "to": next_day})
                counts = self.line.counts(_plant_day(day))
                self._same_summary(report["summary"], counts, f"report of {day}")

        @invariant()
        def every_unit_answers_its_runs(self) -> None:
            for serial in sorted({r.serial for r in self.line.runs}):
                expected = self.line.unit(serial)
                answer = self.http.get(f"/api/v1/units/{serial}")
                assert answer.status_code == 200, answer.text
                unit = answer.json()
                got = (
                    unit["verdict"],
                    unit["attempts"],
                    unit["latest"]["run_id"],
                    (unit["holds"] or {}).get("run_id"),
                )
                want = (
                    expected.verdict,
                    expected.attempts,
                    expected.latest_run_id,
                    expected.holds_run_id,
                )
                assert got == want, (serial, "verdict, attempts, latest, holds", got, want)
            for serial, reviews in self.reviews.items():
                listed = self.http.get(f"/api/v1/units/{serial}/reviews").json()["data"]
                got_reviews = [(r["run_id"], r["decision"]) for r in listed]
                assert got_reviews == reviews, (serial, "reviews", got_reviews, reviews)

        @invariant()
        def the_split_is_each_products_own(self) -> None:
            parameter = COEFFICIENTS[self.steps % len(COEFFICIENTS)]
            by_product = self._split(parameter, by="part_number")
            for product in PRODUCTS:
                expected = self._capability(parameter, product)
                if expected.count:
                    where = f"split of {parameter} by part_number"
                    group = by_product.get(product.part_number)
                    _same_group(group, expected, product, parameter, where)
                    assert group is not None
                    assert group["section"] in (None, product.part_number), (where, group)
                by_station = self._split(parameter, by="station", part_number=product.part_number)
                for station in sorted({r.station_id for r in self.line.runs}):
                    selection = Selection(part_number=product.part_number, station_id=station)
                    lower, upper = bounds(product, _quantity(parameter))
                    expected = self.line.capability(parameter, selection, (lower, upper))
                    if expected.count:
                        where = f"split of {parameter} by station, {product.part_number}"
                        _same_group(by_station.get(station), expected, product, parameter, where)

        @invariant()
        def the_dashboard_shows_today(self) -> None:
            page = self.http.get("/")
            assert page.status_code == 200, page.text
            html = page.text
            today = _plant_day(datetime.now(PLANT_ZONE).date())
            counts = self.line.counts(today)
            tiles = {
                "units-tested": str(counts.units_tested),
                "first-pass-yield": _percent(counts.first_pass_yield),
                "final-yield": _percent(counts.final_yield),
            }
            for tile, want in tiles.items():
                shown = re.search(rf'id="{tile}">([^<]*)<', html)
                assert shown is not None, ("dashboard tile", tile)
                assert shown.group(1) == want, ("dashboard tile", tile, shown.group(1), want)
            rows = _table_rows(html, "summary")
            want_rows = {"all": counts, **self.line.stations(today)}
            assert {name: _row_counts(r) for name, r in rows.items()} == {
                name: _counts_row(c) for name, c in want_rows.items()
            }, "dashboard station rows"
            products = _table_rows(html, "summary products")
            assert {name: _row_counts(r) for name, r in products.items()} == {
                name: _counts_row(c) for name, c in self.line.products(today).items()
            }, "dashboard product rows"
            held = re.search(r"Units on hold \(latest \d+ of (\d+)", html)
            assert (int(held.group(1)) if held else 0) == len(self.line.held_units()), "on hold"
            # Every control chart's centre is one product's mean of today's values.
            for name, centre in re.findall(r"I-MR chart of (\w+),.*?x̄ ([-0-9.e+]+)<", html):
                means = [
                    m
                    for p in PRODUCTS
                    if (
                        m := Capability.of(
                            self.line.values(name, _product_today(p, today)), None, None
                        ).mean
                    )
                    is not None
                ]
                assert any(math.isclose(float(centre), m, rel_tol=5e-4) for m in means), (
                    "dashboard I-MR centre over two products",
                    name,
                    centre,
                    means,
                )

        # -- helpers ---------------------------------------------------------------------

        def _in_turn(self, items: Sequence[T]) -> Sequence[T]:
            """Every one of ``items`` at night; in ``make test`` one a step, in turn (the
            step's other checks cover the rest of the line): each filtered report is a
            report process's work."""
            if NIGHTLY or not items:
                return items
            return [items[self.steps % len(items)]]

        def _tick(self) -> datetime:
            self.clock += timedelta(minutes=2)
            return self.clock

        def _scannable(self) -> list[str]:
            """Units a station lets an operator scan: not scrapped, not waiting for a review
            in rework."""
            return [s for s, m in sorted(self.units.items()) if not (m.blocked or m.scrapped)]

        def _submit(
            self, model: ModelUnit, station: str, started: datetime, *, aborted: bool = False
        ) -> None:
            payload = run_payload(
                model.unit,
                station_id=station,
                started_at=started,
                aborted=aborted,
                passed_before=model.passed_before,
                attempts_before=model.attempts_since_review,
            )
            answer = self.http.post(
                RUNS, json=payload, headers={"Authorization": f"Bearer {self.keys[station]}"}
            )
            assert answer.status_code == 201, (
                f"a valid {model.unit.product.part_number} run refused",
                answer.status_code,
                answer.text,
            )
            self.line.add(Run.of_payload(payload))
            if not aborted:
                model.attempts_since_review += 1
                model.passed_before = model.passed_before or payload["verdict"] == "pass"
                model.blocked = payload["disposition"] == "rework"

        def _report(self, **query: str) -> dict[str, Any]:
            answer = self.http.get(REPORT, params={"format": "json", **query})
            assert answer.status_code == 200, (query, answer.text)
            report: dict[str, Any] = answer.json()
            return report

        def _split(self, parameter: str, **query: str) -> dict[str, dict[str, Any]]:
            """The split's groups by name, each with the product of its ``section`` (None
            when the runs are of one product)."""
            answer = self.http.get(
                SPLIT, params={"parameter": parameter, "format": "json", **query}
            )
            assert answer.status_code == 200, (query, answer.text)
            split = answer.json()
            sections = split["sections"] or [split]
            # Over two products, a section a product: no group outside its own product.
            groups = {}
            for section in sections:
                for group in section["groups"]:
                    assert group["group"] not in groups, ("a group in two sections", query)
                    groups[group["group"]] = group | {"section": section["part_number"]}
            return groups

        def _capability(self, name: str, product: Datasheet) -> Capability:
            limits = bounds(product, _quantity(name))
            return self.line.capability(name, Selection(part_number=product.part_number), limits)

        def _open_holds(self) -> int:
            reviewed = {run_id for reviews in self.reviews.values() for run_id, _ in reviews}
            return sum(
                1
                for r in self.line.latest_attempts().values()
                if not r.passed and r.run_id not in reviewed
            )

        def _same_summary(self, got: dict[str, Any], want: Counts, where: str) -> None:
            for name, value in want.figures().items():
                assert _close(got[name], value), (where, name, got[name], value, _brief(got))

        def _same_rows(
            self, rows: list[dict[str, Any]], key: str, want: dict[str, Counts], where: str
        ) -> None:
            got = {row[key]: row["summary"] for row in rows}
            assert set(got) == set(want), (where, key, sorted(got), sorted(want))
            for name, counts in want.items():
                self._same_summary(got[name], counts, f"{where}, {key} {name}")

    return LineModel


def _units(serial: str, product: Datasheet) -> st.SearchStrategy[Unit]:
    """A unit of ``product`` whose true coefficients lie within its limits, or (a faulty
    unit) one of them up to a quarter of the tolerance beyond a limit."""
    offset_limits = bounds(product, "offset_counts")
    sensitivity_limits = bounds(product, "sensitivity_counts_per_g")

    def within(limits: tuple[float | None, float | None], faulty: bool) -> st.SearchStrategy[float]:
        lower, upper = limits
        assert lower is not None
        assert upper is not None
        if not faulty:
            return st.floats(lower, upper)
        beyond = (upper - lower) / 4
        return st.one_of(
            st.floats(lower - beyond, lower, exclude_max=True),
            st.floats(upper, upper + beyond, exclude_min=True),
        )

    @st.composite
    def unit(draw: st.DrawFn) -> Unit:
        fault = draw(
            st.sampled_from([None, *((f, a) for f in ("offset", "sensitivity") for a in range(3))])
        )
        offset = tuple(draw(within(offset_limits, fault == ("offset", a))) for a in range(3))
        sensitivity = tuple(
            draw(within(sensitivity_limits, fault == ("sensitivity", a))) for a in range(3)
        )
        return Unit(serial, product, offset, sensitivity)  # type: ignore[arg-type]

    return unit()


def _quantity(parameter: str) -> str:
    return "offset_counts" if parameter.startswith("offset") else "sensitivity_counts_per_g"


def _plant_day(day: date) -> Selection:
    """The runs of one day of the plant, from its midnight to the next (in UTC)."""
    since, until = (datetime.combine(d, time(), PLANT_ZONE) for d in (day, day + timedelta(days=1)))
    return Selection(since=since.astimezone(UTC), until=until.astimezone(UTC))


def _product_today(product: Datasheet, today: Selection) -> Selection:
    return Selection(part_number=product.part_number, since=today.since, until=today.until)


def _close(got: float | None, want: float | None) -> bool:
    if got is None or want is None:
        return got is want
    return math.isclose(got, want, rel_tol=RATIO_TOLERANCE, abs_tol=0.0)


def _brief(document: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in document.items() if k not in ("histogram", "distribution")}


def _same_capability(
    got: dict[str, Any], want: Capability, product: Datasheet, name: str, where: str
) -> None:
    limits = bounds(product, _quantity(name))
    context = (where, name, _brief(got), want)
    assert (got["lower"], got["upper"]) == limits, ("limits", context)
    figures = {k: got[k] for k in ("count", "mean", "std", "cp", "cpk", "out_of_limits")}
    _same_figures(figures, want, limits, context)


def _same_group(
    group: dict[str, Any] | None, want: Capability, product: Datasheet, name: str, where: str
) -> None:
    """A split's group: its n, mean, sd, Cpk and values out of limits (it shows no Cp)."""
    assert group is not None, (where, name, "no group", want)
    figures = {"count": group["n"], "mean": group["mean"], "std": group["sd"]}
    figures |= {"cpk": group["cpk"], "out_of_limits": group["out_of_limits"]}
    _same_figures(figures, want, bounds(product, _quantity(name)), (where, name, group, want))


def _same_figures(
    got: dict[str, Any],
    want: Capability,
    limits: tuple[float | None, float | None],
    context: object,
) -> None:
    """Counts exactly. The server sums ``x − c`` and ``(x − c)²`` about the tolerance
    centre c (``docs/report.md``) in its own order: its mean may differ by the rounding of
    that sum (a relative :data:`SUM_ROUNDING` of ``Σ|x − c|``), its variance by the rounding
    of ``Σ(x − c)²`` over ``n − 1``, so its sd by the square root of that
    (``|√a − √b| ≤ √|a − b|``). Cp and Cpk follow: a bound from those two, where the sd
    is well above its own rounding (values that nearly agree leave Cp/Cpk to rounding)."""
    assert (got["count"], got["out_of_limits"]) == (want.count, want.out_of_limits), (
        "count, out of limits",
        context,
    )
    assert want.mean is not None
    lower, upper = limits
    centre = ((lower or 0.0) + (upper or 0.0)) / 2
    std = want.std or 0.0
    mean_tolerance = SUM_ROUNDING * (abs(want.mean - centre) + std) * want.count
    assert abs(got["mean"] - want.mean) <= mean_tolerance, ("mean", context)
    if want.std is None:
        assert got["std"] is None, ("sd of one value", context)
        return
    squares = (want.count - 1) * std**2 + want.count * (want.mean - centre) ** 2
    std_tolerance = math.sqrt(SUM_ROUNDING * squares / (want.count - 1))
    assert got["std"] is not None, ("sd", context)
    assert abs(got["std"] - std) <= std_tolerance, ("sd", std_tolerance, context)
    if std <= 1e6 * std_tolerance:
        return
    for figure in ("cp", "cpk"):
        expected = getattr(want, figure)
        if figure not in got or expected is None:
            continue
        tolerance = mean_tolerance / (3 * std) + 2 * abs(expected) * std_tolerance / std
        assert got[figure] is not None, (figure, context)
        assert abs(got[figure] - expected) <= tolerance + 1e-12, (figure, tolerance, context)


def _percent(ratio: float | None) -> str:
    return "–" if ratio is None else f"{ratio * 100:.1f} %"


def _table_rows(html: str, css_class: str) -> dict[str, list[str]]:
    """The rows of the dashboard's first ``<table class="css_class">``, by first cell."""
    table = re.search(rf'<table class="{css_class}">(.*?)</table>', html, re.S)
    if table is None:
        return {}
    rows = {}
    for row in re.findall(r"<tr>(.*?)</tr>", table.group(1), re.S):
        cells = [
            re.sub(r"<[^>]+>", "", c).strip() for c in re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)
        ]
        if cells:
            rows[cells[0]] = cells[1:]
    return rows


def _row_counts(cells: list[str]) -> tuple[str, ...]:
    """units, passed, failed, runs, retests and aborts of a dashboard row."""
    return (cells[0], cells[1], cells[2], cells[3], cells[7], cells[9])


def _counts_row(counts: Counts) -> tuple[str, ...]:
    return tuple(
        str(v)
        for v in (
            counts.units_tested,
            counts.units_passed,
            counts.units_failed,
            counts.runs,
            counts.retests,
            counts.aborted_runs,
        )
    )
