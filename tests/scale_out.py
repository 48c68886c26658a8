"""Scale-out parts for real: the distribution's pgbouncer and HAProxy with the configuration
of ``deploy/scale-out/``, and ``calstation serve`` processes behind them.

Each starts on free ports with its files in a directory the caller gives, never as the
system's service, and is ended when its block ends. Used by ``tests/test_scale_out.py``
and ``benchmarks/bench_scale_out.py``.
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from string import Template

import httpx
from sqlalchemy import make_url, text

from db import make_engine
from tests.conftest import REPO_ROOT
from tests.servers import free_port

DEPLOY = REPO_ROOT / "deploy" / "scale-out"
#: HAProxy's health check interval (ms): how soon a server gone or back is seen.
CHECK_MS = 500
#: Seconds after which a part that never came up counts as hung.
HUNG_S = 300


def wait_until(check: Callable[[], bool], what: str, process: "subprocess.Popen[bytes]") -> None:
    """Wait for ``check`` to hold; fail if ``process`` ends first or it hangs."""
    deadline = time.monotonic() + HUNG_S
    while not check():
        if process.poll() is not None:
            raise RuntimeError(f"{what} exited {process.returncode}")
        if time.monotonic() > deadline:
            raise RuntimeError(f"{what} did not come up in {HUNG_S} s")
        time.sleep(0.05)


def answers(url: str) -> bool:
    """Whether ``url`` answers 200."""
    try:
        return httpx.get(url, timeout=1).status_code == 200
    except httpx.TransportError:
        return False


def stop(process: "subprocess.Popen[bytes]") -> None:
    """End ``process`` (SIGTERM, then SIGKILL if it lingers)."""
    process.terminate()
    try:
        process.wait(timeout=20)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


@contextmanager
def pgbouncer(database_url: str, pool_size: int = 20) -> Iterator[str]:
    """pgbouncer (``deploy/scale-out/pgbouncer.ini``) before the database at
    ``database_url`` (trust authentication, as the test server's); yields the URL
    through it. Its files are in a temporary directory of their own, which the
    ``postgres`` user it runs as (when started by root) can reach."""
    with tempfile.TemporaryDirectory(prefix="pgbouncer-") as name:
        yield from _pgbouncer(database_url, Path(name), pool_size)


def _pgbouncer(database_url: str, directory: Path, pool_size: int) -> Iterator[str]:
    url = make_url(database_url)
    listen_port = free_port()
    (directory / "userlist.txt").write_text(f'"{url.username}" ""\n')
    config = Template((DEPLOY / "pgbouncer.ini").read_text()).substitute(
        database=url.database,
        host=url.host or "127.0.0.1",
        port=url.port or 5432,
        listen_port=listen_port,
        auth_type="trust",
        directory=directory,
        pool_size=pool_size,
    )
    (directory / "pgbouncer.ini").write_text(config)
    command = ["pgbouncer", "--quiet", str(directory / "pgbouncer.ini")]
    if os.geteuid() == 0:  # pgbouncer refuses to run as root
        directory.chmod(0o755)
        shutil.chown(directory, "postgres")
        command[1:1] = ["-u", "postgres"]
    process = subprocess.Popen(command)
    through = url.set(host="127.0.0.1", port=listen_port).render_as_string(hide_password=False)
    engine = make_engine(through)

    def up() -> bool:
        try:
            with engine.connect() as connection:
                return connection.execute(text("SELECT 1")).scalar_one() == 1
        except Exception:
            return False

    try:
        wait_until(up, "pgbouncer", process)
        engine.dispose()
        yield through
    finally:
        engine.dispose()
        stop(process)


@contextmanager
def haproxy(ports: list[int], directory: Path) -> Iterator[str]:
    """HAProxy (``deploy/scale-out/haproxy.cfg``) before the servers on ``ports``;
    yields its base URL."""
    port = free_port()
    servers = "\n".join(
        f"    server s{i} 127.0.0.1:{each} check inter {CHECK_MS} fall 1 rise 1"
        for i, each in enumerate(ports)
    )
    config = Template((DEPLOY / "haproxy.cfg").read_text()).substitute(
        listen=f"127.0.0.1:{port}", servers=servers
    )
    (directory / "haproxy.cfg").write_text(config)
    with (directory / "haproxy.log").open("ab") as log:
        process = subprocess.Popen(
            ["haproxy", "-f", str(directory / "haproxy.cfg")], stdout=log, stderr=log
        )
    base = f"http://127.0.0.1:{port}"
    try:
        wait_until(lambda: answers(f"{base}/healthz"), "haproxy", process)
        yield base
    finally:
        stop(process)


def start_server(
    url: str, port: int, directory: Path, **settings: str
) -> "subprocess.Popen[bytes]":
    """``calstation serve`` (one worker) on ``port``, its log in ``directory``; returned
    once it answers ``/healthz``."""
    env = {
        **{k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")},
        **{f"CALSTATION_{name.upper()}": value for name, value in settings.items()},
        "CALSTATION_DATABASE_URL": url,
        "PYTHONPATH": str(REPO_ROOT),
    }
    with (directory / f"server-{port}.log").open("ab") as log:
        process = subprocess.Popen(
            [sys.executable, "-m", "station", "serve", "--port", str(port), "--workers", "1"],
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
    try:
        wait_until(lambda: answers(f"http://127.0.0.1:{port}/healthz"), "server", process)
    except RuntimeError:
        stop(process)
        raise
    return process


#: An alert rule that holds over any window of the runs it is given (their offsets spread
#: so that no ten of them reach a Cpk of 10, the highest target a rule takes), so it fires
#: once and never clears.
ALERT_RULES = """webhook = "http://127.0.0.1:{port}/hook"

[[cpk]]
parameter = "offset_x"
runs = {runs}
target = 10
"""


class Webhook:
    """A local receiver of the alert webhook: the bodies posted to it, in order."""

    def __init__(self) -> None:
        posted: list[dict[str, object]] = []
        self.posted = posted

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:
                posted.append(json.loads(self.rfile.read(int(self.headers["Content-Length"]))))
                self.send_response(204)
                self.end_headers()

            def log_message(self, *_: object) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def rules(self, directory: Path, runs: int) -> Path:
        """An alert rules file posting here, whose rule fires once ``runs`` runs are stored."""
        path = directory / "alerts.toml"
        path.write_text(ALERT_RULES.format(port=self.server.server_address[1], runs=runs))
        return path

    def close(self) -> None:
        """Stop receiving."""
        self.server.shutdown()
        self.server.server_close()
