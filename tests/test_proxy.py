"""The TLS proxy of docker-compose.yml for real: nginx (the distribution's, `.ci/run`
installs it) with the repository's ``deploy/proxy/nginx.conf``, its certificate and
password file made by the commands ``docs/api.md`` documents, in front of a real
``calstation serve`` whose reads need a key, and of a stand-in for Prometheus. Only the
names of the compose network (``api``, ``prometheus``), the published ports and the
secrets' folder are replaced by this machine's."""

import http.server
import os
import shutil
import ssl
import subprocess
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest

from db import RunRepository, open_database
from station.results.storage import HttpStore, StoreUnavailableError
from tests.conftest import REPO_ROOT
from tests.db.records import make_record
from tests.servers import HUNG_SERVER_S, free_port, serving

CONF = REPO_ROOT / "deploy" / "proxy" / "nginx.conf"
PROMETHEUS_PAGE = b"prometheus stand-in"
PASSWORD = "p@ss:w/rd"


@dataclass(frozen=True)
class Proxy:
    """The proxy's two doors, the client's trust in its certificate, a station's key."""

    api: str
    prometheus: str
    direct_api: str
    tls: ssl.SSLContext
    certificate: Path
    key: str


def make_secrets(folder: Path) -> None:
    """The certificate, its key and the password file, as docs/api.md makes them."""
    folder.mkdir()
    subprocess.run(
        [
            *("openssl", "req", "-x509", "-newkey", "rsa:3072", "-sha256", "-days", "825"),
            *("-nodes", "-subj", "/CN=calstation"),
            *("-addext", "subjectAltName=DNS:calstation.plant.example,DNS:localhost"),
            *("-keyout", str(folder / "calstation.key"), "-out", str(folder / "calstation.crt")),
        ],
        check=True,
        capture_output=True,
    )
    hashed = subprocess.run(
        ["openssl", "passwd", "-6", "-stdin"],
        input=PASSWORD,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    (folder / "prometheus.htpasswd").write_text(f"prometheus:{hashed}\n")


def configured(conf: str, replacements: dict[str, str]) -> str:
    """``conf`` with each name of the compose deployment replaced by this machine's."""
    for name, here in replacements.items():
        assert name in conf, name
        conf = conf.replace(name, here)
    return conf


class _Prometheus(http.server.BaseHTTPRequestHandler):
    def do_GET(self) -> None:
        self.send_response(200)
        self.send_header("Content-Length", str(len(PROMETHEUS_PAGE)))
        self.end_headers()
        self.wfile.write(PROMETHEUS_PAGE)

    def log_message(self, format: str, *args: object) -> None:
        pass


def _answers(url: str, tls: ssl.SSLContext) -> bool:
    try:
        httpx.get(url, verify=tls, timeout=1)
    except httpx.TransportError:
        return False
    return True


@pytest.fixture(scope="module")
def proxy(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Proxy]:
    nginx = shutil.which("nginx") or (
        "/usr/sbin/nginx" if Path("/usr/sbin/nginx").exists() else None
    )
    if nginx is None:
        pytest.skip("nginx is not installed (.ci/run installs it)")
    root = tmp_path_factory.mktemp("proxy")
    make_secrets(root / "secrets")
    database_url = f"sqlite:///{root / 'calstation.sqlite3'}"
    prometheus = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Prometheus)
    threading.Thread(target=prometheus.serve_forever, daemon=True).start()
    api_door, prometheus_door = free_port(), free_port()
    with serving(database_url, read_requires_key="true") as direct_api:
        database = open_database(database_url)
        with database.session() as session, session.begin():
            key = RunRepository(session).create_key("line1-st1")
        database.dispose()
        (root / "calstation.conf").write_text(
            configured(
                CONF.read_text(),
                {
                    "listen 443 ssl;": f"listen 127.0.0.1:{api_door} ssl;",
                    "listen 9443 ssl;": f"listen 127.0.0.1:{prometheus_door} ssl;",
                    "http://api:8000": direct_api,
                    "http://prometheus:9090": f"http://127.0.0.1:{prometheus.server_port}",
                    "/etc/nginx/secrets": str(root / "secrets"),
                },
            )
        )
        temp = "\n".join(
            f"  {kind}_temp_path {root / kind};" for kind in ("client_body", "proxy", "fastcgi")
        )
        user = "user root;\n" if os.geteuid() == 0 else ""
        (root / "nginx.conf").write_text(
            f"{user}daemon off;\nworker_processes 1;\npid {root / 'nginx.pid'};\n"
            f"error_log {root / 'error.log'};\nevents {{}}\n"
            f"http {{\n  access_log off;\n{temp}\n"
            f"  uwsgi_temp_path {root / 'uwsgi'};\n  scgi_temp_path {root / 'scgi'};\n"
            f"  include {root / 'calstation.conf'};\n}}\n"
        )
        server = subprocess.Popen(
            [nginx, "-p", str(root), "-e", str(root / "error.log"), "-c", str(root / "nginx.conf")],
            stderr=subprocess.DEVNULL,
        )
        certificate = root / "secrets" / "calstation.crt"
        tls = ssl.create_default_context(cafile=certificate)
        api = f"https://localhost:{api_door}"
        try:
            deadline = time.monotonic() + HUNG_SERVER_S
            while not _answers(f"{api}/healthz", tls):
                assert server.poll() is None, (root / "error.log").read_text()
                assert time.monotonic() < deadline, "nginx never answered"
                time.sleep(0.05)
            yield Proxy(
                api, f"https://localhost:{prometheus_door}", direct_api, tls, certificate, key
            )
        finally:
            server.terminate()
            server.wait(timeout=30)
            prometheus.shutdown()
            prometheus.server_close()


def test_the_api_answers_over_tls_and_every_read_needs_a_key(proxy: Proxy) -> None:
    with httpx.Client(base_url=proxy.api, verify=proxy.tls, timeout=HUNG_SERVER_S) as client:
        assert client.get("/healthz").status_code == 200
        assert client.get("/api/v1/units/PT-000001").status_code == 401
        keyed = client.get(
            "/api/v1/units/PT-000001", headers={"Authorization": f"Bearer {proxy.key}"}
        )
        assert keyed.status_code == 404
        assert keyed.json()["detail"]


def test_the_server_metrics_are_prometheus_s_alone(proxy: Proxy) -> None:
    assert httpx.get(f"{proxy.api}/metrics", verify=proxy.tls).status_code == 404
    assert httpx.get(f"{proxy.direct_api}/metrics").status_code == 200


def test_a_body_too_large_is_refused_by_the_api_itself(proxy: Proxy) -> None:
    answer = httpx.post(
        f"{proxy.api}/api/v1/runs",
        content=b"{" + b" " * (1024 * 1024 + 512) + b"}",
        headers={"Authorization": f"Bearer {proxy.key}", "Content-Type": "application/json"},
        verify=proxy.tls,
        timeout=HUNG_SERVER_S,
    )
    assert answer.status_code == 413
    assert answer.headers["content-type"] == "application/json"
    # The API's own words for it, as it answers that body itself.
    assert (
        answer.json()
        == httpx.post(
            f"{proxy.direct_api}/api/v1/runs",
            content=b"{" + b" " * (1024 * 1024 + 512) + b"}",
            headers={"Authorization": f"Bearer {proxy.key}", "Content-Type": "application/json"},
            timeout=HUNG_SERVER_S,
        ).json()
    )


def test_prometheus_answers_only_with_its_password(proxy: Proxy) -> None:
    page = f"{proxy.prometheus}/graph"
    assert httpx.get(page, verify=proxy.tls).status_code == 401
    wrong = httpx.get(page, verify=proxy.tls, auth=("prometheus", "guess"))
    assert wrong.status_code == 401
    right = httpx.get(page, verify=proxy.tls, auth=("prometheus", PASSWORD))
    assert right.status_code == 200
    assert right.content == PROMETHEUS_PAGE


def test_no_door_speaks_plain_http(proxy: Proxy) -> None:
    for door in (proxy.api, proxy.prometheus):
        plain = httpx.get(door.replace("https://", "http://") + "/healthz")
        assert plain.status_code == 400


def test_a_station_that_trusts_the_certificate_stores_its_runs_through_the_proxy(
    proxy: Proxy, monkeypatch: pytest.MonkeyPatch
) -> None:
    record = make_record(serial="PT-000042")
    # A station that does not know the plant's certificate refuses to talk to it.
    monkeypatch.delenv("SSL_CERT_FILE", raising=False)
    untrusting = HttpStore(proxy.api, proxy.key, station_id=record.station_id)
    with pytest.raises(StoreUnavailableError, match="CERTIFICATE_VERIFY_FAILED"):
        untrusting.submit(record)
    untrusting.close()
    # Told where it is (SSL_CERT_FILE in the station's environment), it stores the run.
    monkeypatch.setenv("SSL_CERT_FILE", str(proxy.certificate))
    store = HttpStore(proxy.api, proxy.key, station_id=record.station_id)
    try:
        assert store.submit(record).created
        assert [run.run_id for run in store.history("PT-000042")] == [record.run_id]
    finally:
        store.close()
