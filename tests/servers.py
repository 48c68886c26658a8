"""Server fixtures (a pytest plugin loaded by tests/conftest.py): the API as a real process."""

import os
import socket
import ssl
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import httpx
import pytest

from db import Database, RunRepository
from tests.conftest import REPO_ROOT

STATION = "line1-st1"
#: Seconds after which a started server that never answered counts as hung.
HUNG_SERVER_S = 300

#: The TLS settings of the suite's HTTP clients, made once a process. httpx loads
#: certifi's certificate store into every client it makes unless given a context: some
#: 20–40 ms of CPU a client, which the polls of a starting server (every 50 ms) and of
#: the alert loops paid on every call. The servers here speak plain HTTP anyway.
_TLS = ssl.create_default_context()


def local_client(base_url: str = "", *, timeout: float | None = None) -> httpx.Client:
    """An HTTP client of a server the suite started; its time-out (default
    :data:`HUNG_SERVER_S`) only ends a hung server."""
    return httpx.Client(base_url=base_url, timeout=timeout or HUNG_SERVER_S, verify=_TLS)


def local_get(url: str, **kwargs: Any) -> httpx.Response:
    """``httpx.get`` of a server the suite started, as :func:`local_client`."""
    kwargs.setdefault("timeout", HUNG_SERVER_S)
    return httpx.get(url, verify=_TLS, **kwargs)


@pytest.fixture
def station_key(database: Database) -> str:
    """A valid API key of station ``line1-st1``."""
    with database.session() as session, session.begin():
        return RunRepository(session).create_key(STATION)


@pytest.fixture
def lab_key(database: Database) -> str:
    """A valid API key of lab ``gyro-lab`` (stores gyro fits)."""
    with database.session() as session, session.begin():
        return RunRepository(session).create_key("gyro-lab", "lab")


def free_port() -> int:
    """A TCP port nobody listens on right now."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


@contextmanager
def serving(database_url: str, *, workers: int = 1, **settings: str) -> Iterator[str]:
    """Run ``calstation serve`` as a real process on a free port; yield its base URL.

    ``settings`` become ``CALSTATION_<NAME>`` variables of the server process.
    """
    with server_process(database_url, workers=workers, **settings) as (base, _):
        yield base


@contextmanager
def server_process(
    database_url: str, *, workers: int = 1, **settings: str
) -> Iterator[tuple[str, "subprocess.Popen[bytes]"]]:
    """:func:`serving`, yielding the server's process too (one worker: it serves)."""
    port = free_port()
    env = {
        **{k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")},
        **{f"CALSTATION_{name.upper()}": value for name, value in settings.items()},
        "CALSTATION_DATABASE_URL": database_url,
        "PYTHONPATH": str(REPO_ROOT),
    }
    command = ["serve", "--port", str(port), "--workers", str(workers)]
    # The server's log goes to a file: a pipe nobody reads would fill and block it.
    with tempfile.TemporaryFile() as log:
        server = subprocess.Popen(
            [sys.executable, "-m", "station", *command],
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
        base = f"http://127.0.0.1:{port}"
        try:
            # Not a speed check: a server that is still starting is waited for (a busy
            # two-core machine took 21 s), the bound only ends a server that hangs.
            deadline = time.monotonic() + HUNG_SERVER_S
            with local_client(base, timeout=1) as probe:
                while not _healthy(probe):
                    if server.poll() is not None:
                        log.seek(0)
                        output = log.read().decode(errors="replace")
                        pytest.fail(f"calstation serve exited {server.returncode}: {output}")
                    if time.monotonic() > deadline:
                        pytest.fail(f"calstation serve hung: no /healthz in {HUNG_SERVER_S} s")
                    time.sleep(0.05)
            yield base, server
        finally:
            server.terminate()
            server.wait(timeout=10)


def _healthy(probe: httpx.Client) -> bool:
    try:
        return probe.get("/healthz").status_code == 200
    except httpx.TransportError:
        return False


@pytest.fixture(scope="session")
def live_url(migrated_database: Database, database_url: str) -> Iterator[str]:
    """The server with default settings, on the session's database."""
    with serving(database_url) as base:
        yield base


@pytest.fixture(scope="session")
def keyed_url(migrated_database: Database, database_url: str) -> Iterator[str]:
    """A server whose read endpoints need a station key too."""
    with serving(database_url, read_requires_key="true") as base:
        yield base


@pytest.fixture
def client(database: Database, live_url: str) -> Iterator[httpx.Client]:
    """An HTTP client of the live server; the database is emptied after the test. Its
    time-out only ends a hung server (a busy two-core machine took over 10 s for a
    report): no test's verdict hangs on how loaded the machine is."""
    with local_client(live_url) as client:
        yield client


@pytest.fixture
def quality_key(database: Database) -> str:
    """A valid API key of quality engineer ``qe-ana`` (reviews units on hold)."""
    with database.session() as session, session.begin():
        return RunRepository(session).create_key("qe-ana", "quality")
