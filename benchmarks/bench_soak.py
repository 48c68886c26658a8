"""A week on the line, simulated: stations and a fixture against one server, faults at random.

    python benchmarks/bench_soak.py                   # 7 days × 3 shifts (about 20 min)
    python benchmarks/bench_soak.py --days 1 --shifts 1 --stations 1 --slots 2 --units 2

Real processes throughout: one ``calstation serve`` on its own database (a fresh
PostgreSQL database when ``CALSTATION_TEST_POSTGRES_URL`` names a server, else a SQLite
file), and each shift one ``calstation demo`` per station (the real station on virtual
putters, its operator pulling a cable now and then) and one for a fixture, each station
with its own key, data directory and outbox, sending its runs over HTTP. While a shift
runs, faults are injected at random (seeded):

- ``server-kill``: the server killed (SIGKILL) and started again a few seconds later;
- ``server-hang``: the server stopped (SIGSTOP) for a few seconds, then continued;
- ``database-restart``: every connection to the database dropped and new ones refused
  for a few seconds (PostgreSQL);
- ``disk-full``: a station's data directory (a small tmpfs) filled to the last byte for
  a few seconds, then freed (needs root);
- ``corrupt-file``: a torn and a binary file dropped into a station's outbox;
- ``key-rotation``: a station's key revoked and a new one issued: its runs wait until its
  next shift starts with the new key.

Wall-clock steps are not injected here (libfaketime breaks Python's ``time.sleep``):
a run that a clock stepped back would end before it began is the test
``tests/station/run/test_record.py::test_a_clock_stepped_back_never_ends_a_run_before_it_began``.

After the week every station runs a last, quiet shift, and the harness checks: every
run a station reported is stored exactly once; no run waits in an outbox or was refused
(the injected files, and those only, are set aside as unreadable); the server answered
no request with a 500 (a 503 while the database or the server is down is its documented
answer, counted apart), and logged no unhandled error. It prints a Markdown table
(``--json``: the figures as JSON) and exits 1 if a check failed.
"""

import argparse
import json
import os
import random
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
from sqlalchemy import make_url, text

from db import RunRepository, make_engine, open_database

ROOT = Path(__file__).resolve().parents[1]
FAULTS = (
    "server-kill",
    "server-hang",
    "database-restart",
    "disk-full",
    "corrupt-file",
    "key-rotation",
)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


class Server:
    """``calstation serve`` on the soak's database: started, killed, hung, restarted."""

    def __init__(self, database_url: str, log: Path) -> None:
        self.database_url = database_url
        self.log = log
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.process: subprocess.Popen[bytes] | None = None

    def start(self) -> None:
        env = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
        env.update(CALSTATION_DATABASE_URL=self.database_url, PYTHONPATH=str(ROOT))
        with self.log.open("ab") as log:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "station", "serve", "--port", str(self.port)],
                env=env,
                stdout=log,
                stderr=subprocess.STDOUT,
            )
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            with suppress(httpx.TransportError):
                if httpx.get(f"{self.url}/healthz", timeout=2).status_code == 200:
                    return
            time.sleep(0.1)
        raise RuntimeError("calstation serve did not become healthy within 120 s")

    def kill(self) -> None:
        if self.process is not None:
            self.process.kill()
            self.process.wait()

    def hang(self, seconds: float) -> None:
        assert self.process is not None
        os.kill(self.process.pid, signal.SIGSTOP)
        try:
            time.sleep(seconds)
        finally:
            os.kill(self.process.pid, signal.SIGCONT)

    def stop(self) -> None:
        if self.process is not None:
            self.process.terminate()
            self.process.wait(timeout=30)


@dataclass
class Station:
    """One station of the line: its data directory (a small tmpfs when it can be
    mounted), its key, and what its shifts reported."""

    name: str
    data: Path
    key: str
    slots: int = 1
    mounted: bool = False
    runs: list[str] = field(default_factory=list)
    rescued: int = 0
    #: Starts the station refused because its disk was full (it exits 2 and says so).
    refused_starts: int = 0
    injected: int = 0
    log: list[str] = field(default_factory=list)

    @property
    def outbox(self) -> Path:
        return self.data / "outbox"


#: The file that fills a station's disk while a disk-full fault lasts.
FILLER = "filler"


def _refused_full_disk(code: int, out: str, err: str) -> bool:
    """Whether a demo refused to start, in one line, because its data disk was full."""
    lines = err.strip().splitlines()
    return code == 2 and not out.strip() and bool(lines) and "the disk is full" in lines[-1]


@contextmanager
def soak_database() -> Iterator[str]:
    """A fresh, migrated database for the soak: its URL; dropped at the end."""
    server = os.environ.get("CALSTATION_TEST_POSTGRES_URL")
    if not server:
        with tempfile.TemporaryDirectory() as tmp:
            url = f"sqlite:///{tmp}/soak.sqlite3"
            open_database(url, auto_migrate=True).dispose()
            yield url
        return
    name = f"calstation_soak_{secrets.token_hex(4)}"
    admin = make_engine(server, isolation_level="AUTOCOMMIT")
    with admin.connect() as connection:
        connection.execute(text(f'CREATE DATABASE "{name}"'))
    url = make_url(server).set(database=name).render_as_string(hide_password=False)
    try:
        open_database(url, auto_migrate=True).dispose()
        yield url
    finally:
        with admin.connect() as connection:
            connection.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


def create_key(database_url: str, station: str, revoke: bool = False) -> str:
    database = open_database(database_url)
    try:
        with database.session() as session, session.begin():
            repository = RunRepository(session)
            if revoke:
                repository.revoke_keys(station)
            return repository.create_key(station)
    finally:
        database.dispose()


class Soak:
    """The week: its stations, server, database, faults and readers."""

    def __init__(self, args: argparse.Namespace, database_url: str, root: Path) -> None:
        self.args = args
        self.database_url = database_url
        self.root = root
        self.rng = random.Random(args.seed)
        self.server = Server(database_url, root / "server.log")
        self.faults: Counter[str] = Counter()
        self.statuses: Counter[int] = Counter()
        self.stations = [self._station(f"st-{n}", slots=1) for n in range(1, args.stations + 1)] + (
            [self._station("fx-1", slots=args.slots)] if args.slots > 1 else []
        )
        self.postgres = database_url.startswith("postgresql")
        self._reading = threading.Event()

    def _station(self, name: str, slots: int) -> Station:
        data = self.root / name
        data.mkdir()
        mounted = (
            self.args.disk_faults
            and subprocess.run(
                ["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(data)],
                capture_output=True,
                check=False,
            ).returncode
            == 0
        )
        key = create_key(self.database_url, name)
        return Station(name, data, key, slots=slots, mounted=mounted)

    # -- shifts --------------------------------------------------------------------------

    def shift(self, number: int, *, quiet: bool = False) -> None:
        """Every station's demo for one shift, faults injected meanwhile (unless quiet)."""
        processes = [(s, self._demo(s, number, quiet)) for s in self.stations]
        done = threading.Event()
        injector = threading.Thread(target=self._inject, args=(done,), daemon=True)
        if not quiet:
            injector.start()
        for station, process in processes:
            out, err = process.communicate(timeout=self.args.shift_timeout)
            while _refused_full_disk(process.returncode, out, err):
                # As the operator would: free the disk, start the station again.
                station.refused_starts += 1
                while (station.data / FILLER).exists():
                    time.sleep(0.2)
                process = self._demo(station, number, quiet)
                out, err = process.communicate(timeout=self.args.shift_timeout)
            self._reported(station, process.returncode, out, err)
        done.set()
        if injector.is_alive():
            injector.join()

    def _demo(self, station: Station, number: int, quiet: bool) -> "subprocess.Popen[str]":
        env = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
        env.update(
            PYTHONPATH=str(ROOT),
            CALSTATION_DATA_DIR=str(station.data),
            CALSTATION_SERVER_URL=self.server.url,
            CALSTATION_API_KEY=station.key,
        )
        seed = 100 * (self.stations.index(station) + 1) + number  # new serials each shift
        args = [
            "demo",
            "--json",
            "--units",
            str(1 if quiet else self.args.units * station.slots),
            "--speed",
            str(self.args.speed),
            "--seed",
            str(seed),
            "--station",
            station.name,
            "--pull-cables",
            "0" if quiet else str(self.args.pull_cables),
        ]
        if station.slots > 1:
            args += ["--slots", str(station.slots)]
        return subprocess.Popen(
            [sys.executable, "-m", "station", *args],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )

    def _reported(self, station: Station, code: int, out: str, err: str) -> None:
        station.log.append(err)
        if code == 0:
            station.runs += [unit["run_id"] for unit in json.loads(out)]
            return
        last = err.strip().splitlines()[-1] if err.strip() else ""
        if "saved to " in last:  # stopped holding runs only in memory: put them back
            rescue = Path(last.split("saved to ", 1)[1].split(";", 1)[0])
            for path in rescue.glob("*.json"):
                if not path.name.startswith("journal-"):
                    shutil.move(path, station.outbox / path.name)
                    station.rescued += 1
            station.runs += [u["run_id"] for u in json.loads(out or "[]")]
            return
        raise RuntimeError(f"{station.name}: demo exited {code}: {err[-3000:]}")

    # -- faults --------------------------------------------------------------------------

    def _inject(self, done: threading.Event) -> None:
        """Faults at random moments of the shift; with ``--every-fault``, each kind that
        can be injected here once, in a random order, the last ones maybe after the
        shift's units are done (the next shift meets what they left)."""
        kinds = [k for k in self.args.faults if self._possible(k)]
        if self.args.every_fault:
            plan = self.rng.sample(kinds, len(kinds))
        else:
            plan = [self.rng.choice(kinds) for _ in range(self.args.faults_per_shift) if kinds]
        for kind in plan:
            if done.wait(self.rng.uniform(1.0, 4.0)) and not self.args.every_fault:
                return
            getattr(self, "_" + kind.replace("-", "_"))(self.rng.choice(self.stations))
            self.faults[kind] += 1

    def _possible(self, kind: str) -> bool:
        if kind == "database-restart":
            return self.postgres
        if kind == "disk-full":
            return any(s.mounted for s in self.stations)
        return True

    def _server_kill(self, _: Station) -> None:
        self.server.kill()
        time.sleep(self.rng.uniform(1.0, 3.0))
        self.server.start()

    def _server_hang(self, _: Station) -> None:
        self.server.hang(self.rng.uniform(2.0, 6.0))

    def _database_restart(self, _: Station) -> None:
        name = make_url(self.database_url).database
        admin = make_engine(
            os.environ["CALSTATION_TEST_POSTGRES_URL"], isolation_level="AUTOCOMMIT"
        )
        try:
            with admin.connect() as connection:
                connection.execute(text(f'ALTER DATABASE "{name}" ALLOW_CONNECTIONS false'))
                connection.execute(
                    text(
                        "SELECT pg_terminate_backend(pid) FROM pg_stat_activity "
                        "WHERE datname = :name AND pid <> pg_backend_pid()"
                    ),
                    {"name": name},
                )
                time.sleep(self.rng.uniform(2.0, 4.0))
                connection.execute(text(f'ALTER DATABASE "{name}" ALLOW_CONNECTIONS true'))
        finally:
            admin.dispose()

    def _disk_full(self, station: Station) -> None:
        if not station.mounted:
            return
        filler = station.data / FILLER
        with filler.open("ab", buffering=0) as handle, suppress(OSError):
            while True:
                handle.write(b"\0" * 65536)
        time.sleep(self.rng.uniform(2.0, 4.0))
        filler.unlink()

    def _corrupt_file(self, station: Station) -> None:
        station.outbox.mkdir(parents=True, exist_ok=True)
        stamp = secrets.token_hex(4)
        with suppress(OSError):
            (station.outbox / f"torn-{stamp}.json").write_text('{"run_id": "6f1c', "utf-8")
            (station.outbox / f"binary-{stamp}.json").write_bytes(b"\xff\xfe\x00garbage")
            station.injected += 2

    def _key_rotation(self, station: Station) -> None:
        station.key = create_key(self.database_url, station.name, revoke=True)

    # -- readers -------------------------------------------------------------------------

    @contextmanager
    def readers(self) -> Iterator[None]:
        """A quality engineer reading the pages all week: every answer's status counted."""
        self._reading.set()
        thread = threading.Thread(target=self._read, daemon=True)
        thread.start()
        try:
            yield
        finally:
            self._reading.clear()
            thread.join()

    def _read(self) -> None:
        paths = ["/", "/api/v1/reports/eol?format=json", "/api/v1/runs?limit=50", "/healthz"]
        with httpx.Client(base_url=self.server.url, timeout=10) as client:
            while self._reading.is_set():
                for path in paths:
                    try:
                        self.statuses[client.get(path).status_code] += 1
                    except httpx.TransportError:
                        self.statuses[0] += 1  # the server is down or hung: no answer
                time.sleep(0.5)

    # -- the checks ------------------------------------------------------------------------

    def check(self) -> dict[str, Any]:
        database = open_database(self.database_url)
        try:
            with database.engine.connect() as connection:
                rows = connection.execute(
                    text("SELECT run_id, count(*) FROM runs GROUP BY run_id")
                ).all()
        finally:
            database.dispose()
        stored = {str(run_id).replace("-", ""): count for run_id, count in rows}
        reported = [run.replace("-", "") for s in self.stations for run in s.runs]
        log = self.server.log.read_text(encoding="utf-8", errors="replace")
        waiting = sum(len(list(s.outbox.glob("*.json"))) for s in self.stations)
        refused = sum(len(list((s.outbox / "refused").glob("*.json"))) for s in self.stations)
        unreadable = sum(len(list((s.outbox / "unreadable").glob("*.json"))) for s in self.stations)
        figures = {
            "days": self.args.days,
            "shifts": self.args.days * self.args.shifts,
            "stations": len(self.stations),
            "runs reported": len(reported),
            "runs stored": sum(stored.values()),
            "missing": len([r for r in reported if r not in stored]),
            "stored twice": len([r for r, n in stored.items() if n > 1]),
            "waiting in an outbox": waiting,
            "refused": refused,
            "unreadable (injected)": f"{unreadable} ({sum(s.injected for s in self.stations)})",
            "rescued from memory": sum(s.rescued for s in self.stations),
            "starts refused (disk full)": sum(s.refused_starts for s in self.stations),
            "faults": dict(sorted(self.faults.items())),
            "cable pulls": sum(e.count("lost the unit") for s in self.stations for e in s.log),
            "answers 500": self.statuses[500],
            "answers 503": self.statuses[503],
            "no answer (server down or hung)": self.statuses[0],
            "unhandled errors logged": log.count("Traceback"),
        }
        figures["ok"] = (
            figures["missing"] == 0
            and figures["stored twice"] == 0
            and waiting == 0
            and refused == 0
            and unreadable == sum(s.injected for s in self.stations)
            and self.statuses[500] == 0
            and figures["unhandled errors logged"] == 0
        )
        return figures

    def close(self) -> None:
        self.server.stop()
        for station in self.stations:
            if station.mounted:
                subprocess.run(["umount", "-l", str(station.data)], check=False)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=int, default=7)
    parser.add_argument("--shifts", type=int, default=3, help="shifts a day")
    parser.add_argument("--stations", type=int, default=3, help="one-port stations")
    parser.add_argument("--slots", type=int, default=4, help="the fixture's slots (1: none)")
    parser.add_argument("--units", type=int, default=4, help="units per station (and slot) a shift")
    parser.add_argument("--speed", type=float, default=30.0, help="virtual clock speed")
    parser.add_argument("--pull-cables", type=float, default=0.03)
    parser.add_argument("--faults", nargs="*", default=list(FAULTS), choices=FAULTS)
    parser.add_argument("--faults-per-shift", type=int, default=3)
    parser.add_argument(
        "--every-fault", action="store_true", help="each kind of fault once a shift instead"
    )
    parser.add_argument("--no-disk-faults", dest="disk_faults", action="store_false")
    parser.add_argument("--shift-timeout", type=float, default=900.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = parser.parse_args()
    started = time.monotonic()
    with soak_database() as url, tempfile.TemporaryDirectory() as tmp:
        soak = Soak(args, url, Path(tmp))
        try:
            soak.server.start()
            with soak.readers():
                for number in range(args.days * args.shifts):
                    soak.shift(number + 1)
                soak.shift(0, quiet=True)  # the last shift: every outbox drains
                time.sleep(1.0)
            figures = soak.check()
        finally:
            soak.close()
    figures["wall time"] = f"{time.monotonic() - started:.0f} s"
    if args.json:
        print(json.dumps(figures))
    else:
        print("| figure | value |\n| --- | --- |")
        for name, value in figures.items():
            print(f"| {name} | {value} |")
    sys.exit(0 if figures["ok"] else 1)


if __name__ == "__main__":
    main()
