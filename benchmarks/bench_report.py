"""End-of-line report speed: every section over a large line history on PostgreSQL.

    python benchmarks/bench_report.py                   # 1,000,000 runs (about 2 minutes to load)
    python benchmarks/bench_report.py --runs 100000

The history is generated inside the database (``INSERT … SELECT generate_series``): N
runs of about 0.9·N units at four stations by seven operators in three lots, of the two
shipped products (DIXX-A12, DIXX-D16: one unit in three is a D16), one retest per ten runs,
seven poses per run, one to three failure reasons per failing run; then
the report's facts and roll-ups are built from it by :func:`db.rollups.rebuild` (as the
migration does for a database that has runs). It lives in a schema of its own
(``bench_report_<pid>``), dropped at the end. The server comes from
``CALSTATION_BENCH_POSTGRES_URL`` (default: ``CALSTATION_TEST_POSTGRES_URL``, else
``postgresql+psycopg://postgres@127.0.0.1:5432/test``).

Each section's query is timed (best of ``--repeat``), then the whole report as the API
builds it (every section, the unit list cut to its latest 1,000 units), over every run,
over one day, and over two days that start and end at noon (two partial days
aggregated from their runs, one whole day from the roll-ups).

Then the pages as the server renders them, each timed (query and rendering) and weighed:
the report's HTML page over every run as the server answers ``format=html`` (the held
units, 50 a page: page 1 in UTC, in a plant zone with three shifts, and page 1,000), and
with every unit listed (``list=all``: cut to 1,000 units; uncut up to 100,000 runs), a
retested unit's page (``/units/{serial}``) and its certificate, and the line dashboard
(one day, and the units on hold of any day).
"""

import argparse
import os
import time
from collections.abc import Callable
from datetime import UTC, datetime
from datetime import time as clock
from functools import partial
from typing import Any

from sqlalchemy import insert, make_url, text

from api.report_bodies import dashboard_body, split_body
from api.routes.alerts import LISTED_ALERTS
from api.routes.reports import PAGE_UNITS
from db import RunRepository, make_engine, open_database
from db.models import StoredLimitsProfile
from db.report import (
    CYCLE_RUNS,
    ReportQueries,
    eol_report,
    evaluate,
    first_moving_ranges,
    latest_chart_points,
    recent_alerts,
    station_health,
)
from db.rollups import rebuild
from db.store import certificate_run, profile_row, stored_profiles
from station.domain.product.limits import load_profile
from station.domain.quality.alerts import parse_alert_rules
from station.domain.quality.figures import ReportFilter
from station.domain.quality.parameters import profile_bounds
from station.domain.quality.station_health import StationHealth
from station.report.html import alerts_page, certificate_page, station_page, unit_page
from station.report.render import render

DEFAULT_URL = "postgresql+psycopg://postgres@127.0.0.1:5432/test"
CODES = "ARRAY['offset','sensitivity','verification_error','pose_noise','gyro_bias','link_loss']"


def fill(connection: Any, runs: int, sha256: str) -> None:
    """Generate ``runs`` runs with their poses and failure reasons in SQL."""
    connection.execute(
        text("""
        INSERT INTO run_ids (run_pk, run_id, started_at)
        SELECT g, md5(g::text)::uuid, timestamptz '2026-01-01 00:00Z' + g * interval '40 seconds'
        FROM generate_series(1, :runs) AS g
        """),
        {"runs": runs},
    )
    connection.execute(text("SELECT setval('run_ids_run_pk_seq', :runs)"), {"runs": runs})
    connection.execute(
        text("""
        INSERT INTO runs (id, run_id, serial, station_id, operator_id, lot, started_at, finished_at,
            received_at, software_version, algorithm, model, limits_name, limits_version,
            limits_sha256, verdict, offset_x, offset_y, offset_z, sensitivity_x,
            sensitivity_y, sensitivity_z, matrix, residual_rms_mg, residual_max_mg,
            condition_number, verification_error_mg, gyro, record_sha256, part_number)
        SELECT g, md5(g::text)::uuid,
            'PT-' || lpad((g - (g % 10 = 0)::int)::text, 8, '0'),
            'line1-st' || (g % 4 + 1), 'op-' || (g % 7 + 1), 'lot-' || (g / 100000 % 3 + 1),
            t, t + make_interval(secs => 90 + g % 20), t + interval '100 seconds',
            '1.4.0', 'autocal-ls', 'six', 'kxm52-production', '1', :sha,
            CASE WHEN g % 10 = 9 OR g % 37 = 0 THEN 'fail' ELSE 'pass' END,
            2048 + 60 * (random() + random() + random() - 1.5),
            2048 + 60 * (random() + random() + random() - 1.5),
            2048 + 60 * (random() + random() + random() - 1.5),
            819.2 + 8 * (random() + random() + random() - 1.5),
            819.2 + 8 * (random() + random() + random() - 1.5),
            819.2 + 8 * (random() + random() + random() - 1.5),
            '[[0.00122, 0, 0], [0, 0.00122, 0], [0, 0, 0.00122]]'::jsonb,
            0.4, 0.9, 3.2, 12 * random() + 10 * random(),
            jsonb_build_object(
                'bias', jsonb_build_object('x', 2 * (random() - 0.5), 'y', 2 * (random() - 0.5),
                                           'z', 2 * (random() - 0.5)),
                'noise', jsonb_build_object('x', 0.05, 'y', 0.05, 'z', 0.06)),
            md5(g::text) || md5(g::text),
            CASE WHEN (g - (g % 10 = 0)::int) % 3 = 0 THEN 'DIXX-D16' ELSE 'DIXX-A12' END
        FROM generate_series(1, :runs) AS g,
             LATERAL (SELECT timestamptz '2026-01-01 00:00Z' + g * interval '40 seconds') AS s(t)
        """),
        {"runs": runs, "sha": sha256},
    )
    connection.execute(text("ANALYZE runs"))
    connection.execute(
        text("""
        INSERT INTO poses (run_pk, started_at, index, name, role, mean_x, mean_y, mean_z, std_x,
            std_y, std_z, sample_count, gyro_x, gyro_y, gyro_z, temperature_c, crc_errors, gaps,
            resyncs, lost_samples, replaced)
        SELECT r.id, r.started_at, i, 'pose' || i, CASE WHEN i = 6 THEN 'verify' ELSE 'fit' END,
            2048 + 800 * sin(i), 2048 + 800 * cos(i), 2048, 1 + 2 * random(), 1 + 2 * random(),
            1 + 2 * random(), 1024, 0.01, -0.02, 0.005, 24.5, 0, 0, 0, 0, '[]'::jsonb
        FROM runs r, generate_series(0, 6) AS i
        """)
    )
    connection.execute(
        text(f"""
        INSERT INTO run_failures (run_pk, position, code, message)
        SELECT g, k, ({CODES})[1 + (g / 10 + k) % 6], 'generated'
        FROM generate_series(1, :runs) AS g, generate_series(0, 2) AS k
        WHERE (g % 10 = 9 OR g % 37 = 0) AND k <= g % 3
        """),
        {"runs": runs},
    )
    connection.execute(text("ANALYZE runs; ANALYZE poses; ANALYZE run_failures"))


def derive(connection: Any) -> None:
    """Build the report's facts and roll-ups from the generated runs."""
    connection.execute(
        insert(StoredLimitsProfile), profile_row(load_profile())
    )  # as the first run stored it
    rebuild(connection)
    connection.execute(text("ANALYZE run_facts; ANALYZE report_counts"))
    connection.execute(text("ANALYZE report_failures; ANALYZE report_parameters"))


def best(repeat: int, action: Callable[[], object]) -> float:
    """Best wall time of ``repeat`` calls, seconds."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return min(times)


#: A plant's three shifts, for the report page with a trend per shift.
SHIFTS = (clock(6), clock(14), clock(22))

#: Above this many runs the report page that lists every unit is not built (hundreds of
#: megabytes of HTML); its size grows with the units, as the smaller runs show.
EVERY_UNIT_PAGE_RUNS = 100_000


def _health(session: Any) -> StationHealth:
    health = station_health(session, "line1-st1")
    assert health is not None
    return health


#: The rules an alert round checks in the bench: one of each kind that reads runs.
ALERT_RULES = """
webhook = "http://127.0.0.1:9/hook"
[[yield]]
station = "line1-st1"
units = 100
goal = 0.9
[[silent]]
station = "line1-st1"
[[western_electric]]
parameter = "offset_x"
runs = 50
[[cpk]]
parameter = "sensitivity_z"
runs = 100
"""


def _alert_round(session: Any, at: datetime) -> str:
    """One round of the server's alert loop over the history (what it fires is rolled
    back, so each repeat judges the same), and the alerts page it then shows."""
    evaluate(session, parse_alert_rules(ALERT_RULES, "bench"), at)
    page = alerts_page(recent_alerts(session, LISTED_ALERTS), "UTC", 1)
    session.rollback()
    return page


def pages(session: Any, repeat: int, runs: int) -> None:
    """The HTML pages over the generated history: seconds to build, and kB."""
    repository = RunRepository(session)
    serial = "PT-00000009"  # failed, then passed at its retest (run 10)
    at = datetime(2026, 6, 1, 12, tzinfo=UTC)

    def certificate() -> str:
        found = certificate_run(repository, serial)
        assert found is not None
        run, earlier = found
        profile = stored_profiles(session, [run.limits.sha256]).get(run.limits.sha256)
        return certificate_page(run, profile, at, repository.latest_gyro_fit(serial), earlier)

    def served(zone: str = "UTC", shifts: tuple[clock, ...] = (), page: int = 1) -> str:
        # As ``GET /api/v1/reports/eol?format=html`` builds it (api.report_bodies.eol_body).
        report = eol_report(
            session,
            ReportFilter(),
            unit_limit=PAGE_UNITS,
            unit_offset=(page - 1) * PAGE_UNITS,
            held_only=True,
            zone=zone,
            shifts=shifts,
        )
        return render(report, "html")

    rows: list[tuple[str, Callable[[], str], int]] = [
        ("**report page as served (`format=html`: held units, 50 a page)**", served, repeat),
        (
            "report page as served, plant zone Europe/Berlin (the 31 days' trend from the runs)",
            lambda: served("Europe/Berlin"),
            repeat,
        ),
        (
            "report page as served, UTC with three shifts (the trend per shift from the runs)",
            lambda: served(shifts=SHIFTS),
            repeat,
        ),
        (
            "report page as served, Europe/Berlin with three shifts (one scan for both trends)",
            lambda: served("Europe/Berlin", SHIFTS),
            repeat,
        ),
        ("report page as served, page 1,000 of the held units", lambda: served(page=1000), repeat),
        (
            "report page, every run, all units listed, 1,000 of them (`list=all&units=1000`)",
            lambda: render(eol_report(session, ReportFilter(), unit_limit=1000), "html"),
            repeat,
        ),
        (
            f"unit page `/units/{serial}` (2 runs)",
            lambda: unit_page(repository.history(serial), at),
            repeat,
        ),
        (f"certificate of {serial} (earlier run listed)", certificate, repeat),
        (
            "split of offset_x by station (`/api/v1/reports/split`, the latest 20,000 runs)",
            lambda: split_body(repository, ReportFilter(), "offset_x", "station", "html", "UTC"),
            repeat,
        ),
        (
            "station health `/stations/line1-st1` (golden checks, the latest 2,000 runs)",
            lambda: station_page(_health(session), "UTC", CYCLE_RUNS),
            repeat,
        ),
        (
            "dashboard (one day, 50 latest of the units on hold)",
            lambda: dashboard_body(repository, at),
            repeat,
        ),
        (
            "an alert round (a yield, a silent, a Western Electric and a Cpk rule), then "
            "`/alerts` (the latest 100)",
            lambda: _alert_round(session, at),
            repeat,
        ),
    ]
    if runs <= EVERY_UNIT_PAGE_RUNS:
        rows.insert(
            6,
            (
                "report page, every run, every unit listed (`list=all&units=1000000`)",
                lambda: render(eol_report(session, ReportFilter()), "html"),
                1,
            ),
        )
    print(f"\n| page | best of {repeat} (s) | size (kB) |")
    print("|---|---|---|")
    for name, page, times in rows:
        start = time.perf_counter()
        html = page()
        first = time.perf_counter() - start
        seconds = min(first, best(times - 1, page)) if times > 1 else first
        print(f"| {name} | {seconds:.3f} | {len(html.encode()) / 1000:,.1f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--schema", help="reuse this schema, generated by an earlier --keep run")
    parser.add_argument("--keep", action="store_true", help="leave the generated schema in place")
    args = parser.parse_args()
    server = os.environ.get(
        "CALSTATION_BENCH_POSTGRES_URL", os.environ.get("CALSTATION_TEST_POSTGRES_URL", DEFAULT_URL)
    )
    schema = args.schema or f"bench_report_{os.getpid()}"
    admin = make_engine(server, isolation_level="AUTOCOMMIT")
    if not args.schema:
        with admin.connect() as connection:
            connection.execute(text(f'CREATE SCHEMA "{schema}"'))
    url = make_url(server).update_query_dict({"options": f"-csearch_path={schema}"})
    try:
        database = open_database(url.render_as_string(hide_password=False), auto_migrate=True)
        start = time.perf_counter()
        if not args.schema:
            with database.engine.begin() as connection:
                fill(connection, args.runs, load_profile().sha256)
        load_s = time.perf_counter() - start
        if not args.schema:
            with database.engine.begin() as connection:
                derive(connection)
        derive_s = time.perf_counter() - start - load_s
        bounds = profile_bounds(load_profile())
        with database.session() as session:
            runs, poses = session.execute(
                text("SELECT (SELECT count(*) FROM runs), (SELECT count(*) FROM poses)")
            ).one()
            q = ReportQueries(session, ReportFilter())
            day = ReportQueries(
                session,
                ReportFilter(
                    since=datetime(2026, 1, 5, tzinfo=UTC), until=datetime(2026, 1, 6, tzinfo=UTC)
                ),
            )
            sections: list[tuple[str, Callable[[], object]]] = [
                ("counts, yields, limits profiles (per station and line)", q.station_counts),
                ("counts and yields per product (two products)", q.product_counts),
                ("failure Pareto", q.first_failures),
                ("parameters: all 16 (statistics, histograms)", partial(q.parameters, bounds)),
                (
                    "control-chart limits (first run's moving ranges)",
                    lambda: first_moving_ranges(session, q.conditions),
                ),
                (
                    "control-chart points (200)",
                    lambda: latest_chart_points(session, q.conditions, 200),
                ),
                ("latest 1,000 units", lambda: q.latest_runs(1000)),
                ("every unit (ship/hold list)", lambda: q.latest_runs(None)),
            ]
            print(
                f"{runs:,} runs, {poses:,} poses; generated in {load_s:.0f} s, "
                f"facts and roll-ups built in {derive_s:.0f} s\n"
            )
            print(f"| section | best of {args.repeat} (s) |")
            print("|---|---|")
            for name, action in sections:
                print(f"| {name} | {best(args.repeat, action):.3f} |")
            whole = best(
                args.repeat,
                lambda: eol_report(session, ReportFilter(), unit_limit=1000),
            )
            print(f"| **whole report, every run (units cut to 1,000)** | **{whole:.3f}** |")
            one_day = best(args.repeat, lambda: eol_report(session, day.filter))
            print(f"| whole report, one day (2,160 runs, every unit) | {one_day:.3f} |")
            noon = ReportFilter(
                since=datetime(2026, 1, 5, 12, tzinfo=UTC),
                until=datetime(2026, 1, 7, 12, tzinfo=UTC),
            )
            two_days = best(args.repeat, lambda: eol_report(session, noon))
            print(f"| whole report, noon to noon over two days (4,320 runs) | {two_days:.3f} |")
            pages(session, args.repeat, runs)
        database.dispose()
    finally:
        if args.keep or args.schema:
            print(f"\nschema {schema} kept (--schema {schema} to reuse it)")
        else:
            with admin.connect() as connection:
                connection.execute(text(f'DROP SCHEMA "{schema}" CASCADE'))
        admin.dispose()


if __name__ == "__main__":
    main()
