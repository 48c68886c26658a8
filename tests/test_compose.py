"""docker-compose.yml: the shape the plant deploys, read as YAML (and checked by
``docker compose config`` where Docker Compose is installed)."""

import json
import os
import re
import shlex
import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml

from api.settings import ApiSettings
from station.cli.main import build_app
from tests.conftest import REPO_ROOT

COMPOSE = REPO_ROOT / "docker-compose.yml"


@pytest.fixture(scope="module")
def services() -> dict[str, Any]:
    document = yaml.safe_load(COMPOSE.read_text())
    assert set(document["services"]) == {"db", "migrate", "api", "prometheus", "backup", "proxy"}
    assert {"pgdata", "backups"} <= set(document["volumes"])
    services: dict[str, Any] = document["services"]
    return services


def _command(service: dict[str, Any]) -> list[str]:
    command = service["command"]
    return command if isinstance(command, list) else shlex.split(command)


def test_postgres_is_healthy_only_over_tcp_and_has_a_volume(services: dict[str, Any]) -> None:
    db = services["db"]
    assert db["image"].startswith("postgres:")
    check = db["healthcheck"]
    # The image's temporary init server listens on the Unix socket only: over TCP,
    # pg_isready answers for the real server.
    assert re.search(r"pg_isready .*-h (127\.0\.0\.1|localhost|db)\b", " ".join(check["test"]))
    assert {"interval", "timeout", "retries", "start_period"} <= set(check)
    assert any(v.endswith(":/var/lib/postgresql/data") for v in db["volumes"])


def test_migrate_runs_after_the_database_is_healthy(services: dict[str, Any]) -> None:
    migrate = services["migrate"]
    assert _command(migrate) == ["calstation", "db", "upgrade"]
    assert migrate["depends_on"]["db"]["condition"] == "service_healthy"
    assert migrate["restart"] in {"no", "on-failure"}


def test_the_api_waits_for_a_healthy_database_and_a_finished_migration(
    services: dict[str, Any],
) -> None:
    api = services["api"]
    assert api["depends_on"] == {
        "db": {"condition": "service_healthy"},
        "migrate": {"condition": "service_completed_successfully"},
    }
    command = _command(api)
    assert command[:2] == ["calstation", "serve"]
    assert int(command[command.index("--workers") + 1]) > 1
    assert command[command.index("--host") + 1] == "0.0.0.0"
    assert "/healthz" in " ".join(api["healthcheck"]["test"])


def test_the_serve_command_takes_the_options_compose_gives(services: dict[str, Any]) -> None:
    serve = next(
        c
        for c in build_app("serve").registered_commands
        if c.callback and c.callback.__name__ == "serve"
    )
    assert serve.callback is not None
    options = {f"--{name.replace('_', '-')}" for name in serve.callback.__annotations__}
    given = {arg for arg in _command(services["api"]) if arg.startswith("--")}
    assert given <= options


def test_every_calstation_variable_is_a_real_setting_and_urls_match_the_database(
    services: dict[str, Any],
) -> None:
    db_env = services["db"]["environment"]
    known = {f"CALSTATION_{name.upper()}" for name in ApiSettings.model_fields}
    for name in ("migrate", "api", "backup"):
        env = services[name]["environment"]
        ours = {variable for variable in env if variable.startswith("CALSTATION_")}
        assert ours <= known, ours - known
        url = env["CALSTATION_DATABASE_URL"]
        # No password in the URL: the app escapes CALSTATION_DATABASE_PASSWORD itself.
        match = re.fullmatch(r"postgresql\+psycopg://(\w+)@db:5432/(\w+)", url)
        assert match is not None, url
        assert match[1] == db_env["POSTGRES_USER"]
        assert match[2] == db_env["POSTGRES_DB"]
        assert env["CALSTATION_DATABASE_PASSWORD"] == db_env["POSTGRES_PASSWORD"]


def _max_connections(db: dict[str, Any]) -> int:
    given = re.search(r"max_connections=(\d+)", " ".join(_command(db)))
    return int(given[1]) if given else 100  # PostgreSQL's default


def test_the_api_workers_pools_fit_in_postgresqls_connections(services: dict[str, Any]) -> None:
    api = services["api"]
    command = _command(api)
    workers = int(command[command.index("--workers") + 1])
    settings = ApiSettings.model_validate(
        {k.removeprefix("CALSTATION_").lower(): v for k, v in api["environment"].items()}
    )
    per_worker = settings.write_pool_size + settings.read_pool_size + settings.report_pool_size
    budget = workers * per_worker
    # PostgreSQL's superuser_reserved_connections, a migrate or keys create, the backup
    reserved = 3 + 1 + 1
    assert budget + reserved <= 0.8 * _max_connections(services["db"])  # 20 % to spare
    # The budget written in the file's comment is the one the settings give.
    assert f"= {budget}" in COMPOSE.read_text()


def _compose() -> list[str] | None:
    """Docker Compose v2 (``docker compose``), else the distribution's ``docker-compose``."""
    for command in (["docker", "compose"], ["docker-compose"]):
        try:
            found = subprocess.run([*command, "version"], capture_output=True, timeout=30)
        except FileNotFoundError:
            continue
        if found.returncode == 0:
            return command
    return None


def test_docker_compose_accepts_the_file() -> None:
    compose = _compose()
    if compose is None:
        pytest.skip("neither docker compose nor docker-compose is installed (.ci/run installs it)")
    checked = subprocess.run(
        [*compose, "-f", str(COMPOSE), "config", "--quiet"],
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, "POSTGRES_PASSWORD": "p@ss:w/rd"},
    )
    assert checked.returncode == 0, checked.stderr


def test_both_app_services_build_the_image_of_the_dockerfile(services: dict[str, Any]) -> None:
    dockerfile = (REPO_ROOT / "Dockerfile").read_text()
    for name in ("migrate", "api", "backup"):
        assert services[name]["build"] == "."
    for package in ("station", "api", "db"):
        assert f"COPY {package} ./{package}" in dockerfile
    assert Path(REPO_ROOT / ".dockerignore").is_file()


def test_prometheus_scrapes_the_api_with_the_files_in_the_repository(
    services: dict[str, Any],
) -> None:
    prometheus = services["prometheus"]
    mounted = {}
    for volume in prometheus["volumes"]:
        source, target, *_ = volume.split(":")
        if source.startswith("./"):
            assert (REPO_ROOT / source).is_file(), source
            mounted[target] = REPO_ROOT / source
    config = yaml.safe_load(mounted["/etc/prometheus/prometheus.yml"].read_text())
    assert config["rule_files"] == ["/etc/prometheus/alerts.yml"]
    assert "/etc/prometheus/alerts.yml" in mounted
    server = next(j for j in config["scrape_configs"] if j["job_name"] == "calstation-server")
    (api_port,) = services["api"]["expose"]
    assert server["static_configs"][0]["targets"] == [f"api:{api_port}"]
    assert server["metrics_path"] == "/metrics"
    assert prometheus["depends_on"]["api"]["condition"] == "service_healthy"


def test_only_the_proxy_publishes_ports(services: dict[str, Any]) -> None:
    published = {name for name, service in services.items() if "ports" in service}
    assert published == {"proxy"}
    assert not any(service.get("network_mode") == "host" for service in services.values())


def test_every_read_needs_a_key(services: dict[str, Any]) -> None:
    env = services["api"]["environment"]
    settings = ApiSettings.model_validate(
        {k.removeprefix("CALSTATION_").lower(): v for k, v in env.items()}
    )
    assert settings.read_requires_key is True


PROXY_CONF = "/etc/nginx/conf.d/default.conf"
SECRETS = "/etc/nginx/secrets"


def _servers(conf: str) -> dict[int, str]:
    """Each ``server`` block of an nginx configuration by the port it listens on."""
    blocks = {}
    for match in re.finditer(r"^server \{\n(.*?)^\}", conf, re.S | re.M):
        listen = re.search(r"^\s*listen (\d+) ssl;", match[1], re.M)
        assert listen is not None, f"a server without TLS: {match[1][:80]}"
        blocks[int(listen[1])] = match[1]
    return blocks


@pytest.fixture(scope="module")
def proxy(services: dict[str, Any]) -> tuple[dict[str, Any], str]:
    """The proxy's service and its nginx configuration (the repository's file)."""
    service = services["proxy"]
    mounts = {target: source for source, target, *_ in (v.split(":") for v in service["volumes"])}
    source = mounts[PROXY_CONF]
    assert source.startswith("./")
    return service, (REPO_ROOT / source).read_text(encoding="utf-8")


def test_the_proxy_terminates_tls_for_the_api_and_prometheus(
    services: dict[str, Any], proxy: tuple[dict[str, Any], str]
) -> None:
    service, conf = proxy
    servers = _servers(conf)
    published = {int(p.split(":")[-1]): int(p.split(":")[0]) for p in service["ports"]}
    # Every published port is a TLS server of the configuration, and nothing else is.
    assert set(published) == set(servers)
    (api_port,) = services["api"]["expose"]
    (prometheus_port,) = services["prometheus"]["expose"]
    upstreams = {
        port: set(re.findall(r"proxy_pass http://([\w.-]+:\d+);", block))
        for port, block in servers.items()
    }
    assert sorted(upstreams.values(), key=sorted) == [
        {f"api:{api_port}"},
        {f"prometheus:{prometheus_port}"},
    ]
    # The certificate and key are the mounted secrets', and no protocol older than TLS 1.2.
    assert re.search(rf"^ssl_certificate\s+{SECRETS}/\S+\.crt;", conf, re.M)
    assert re.search(rf"^ssl_certificate_key\s+{SECRETS}/\S+\.key;", conf, re.M)
    protocols = re.search(r"^ssl_protocols\s+([^;]+);", conf, re.M)
    assert protocols is not None
    assert set(protocols[1].split()) <= {"TLSv1.2", "TLSv1.3"}
    mounts = {target: source for source, target, *_ in (v.split(":") for v in service["volumes"])}
    assert mounts[SECRETS] == "./deploy/proxy/secrets"
    assert "/deploy/proxy/secrets/" in (REPO_ROOT / ".gitignore").read_text().splitlines()


def test_prometheus_answers_through_the_proxy_only_with_a_password(
    proxy: tuple[dict[str, Any], str],
) -> None:
    _, conf = proxy
    (prometheus,) = [b for b in _servers(conf).values() if "prometheus:" in b]
    assert re.search(r"^\s*auth_basic\s+\"[^\"]+\";", prometheus, re.M)
    assert re.search(rf"^\s*auth_basic_user_file\s+{SECRETS}/\S+;", prometheus, re.M)
    # The API's server neither asks a password (the API's own keys do) nor hands out
    # the server's metrics, which Prometheus scrapes on the compose network.
    (api,) = [b for b in _servers(conf).values() if "api:" in b]
    assert "auth_basic" not in api
    assert re.search(r"location = /metrics \{\s*return 404;", api)


def test_the_proxy_refuses_a_body_too_large_as_the_api_does_and_streams_events(
    services: dict[str, Any], proxy: tuple[dict[str, Any], str]
) -> None:
    _, conf = proxy
    (api,) = [b for b in _servers(conf).values() if "api:" in b]
    size = re.search(r"client_max_body_size (\d+)m;", api)
    assert size is not None
    max_body = int(services["api"]["environment"]["CALSTATION_MAX_BODY_BYTES"])
    assert int(size[1]) * 1024 * 1024 == max_body
    assert "error_page 413 = @too_large;" in api
    answer = re.search(r"location @too_large \{.*?return 413 '([^']*)';", api, re.S)
    assert answer is not None
    assert answer[1] == json.dumps(
        {"detail": f"request body larger than {max_body} bytes"}, separators=(",", ":")
    )
    events = re.search(r"location /api/v1/events \{(.*?)\}", api, re.S)
    assert events is not None
    assert "proxy_buffering off;" in events[1]
    # A location that sets a header drops the server's: the forwarded ones are set again.
    assert "X-Forwarded-For" in events[1]


def test_a_backup_a_day_with_calstation_db_backup_into_its_volume(
    services: dict[str, Any],
) -> None:
    backup = services["backup"]
    script = " ".join(_command(backup))
    assert re.search(r"calstation db backup \"?/backups/", script)
    assert "calstation db partitions;" in script  # the years ahead, the same round
    assert "sleep 86400" in script
    assert (
        backup["environment"]["CALSTATION_DATABASE_URL"]
        == (services["api"]["environment"]["CALSTATION_DATABASE_URL"])
    )
    assert "backups:/backups" in backup["volumes"]
    assert backup["depends_on"]["migrate"]["condition"] == "service_completed_successfully"
    # The image's user owns the directory, so a fresh volume there is writable for it.
    assert "chown calstation /backups" in (REPO_ROOT / "Dockerfile").read_text()
    # The image has the client tools the backup runs.
    assert "postgresql-client" in (REPO_ROOT / "Dockerfile").read_text()
