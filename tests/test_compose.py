"""docker-compose.yml: the shape the plant deploys, read as YAML (and checked by
``docker compose config`` where Docker Compose is installed)."""

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
    assert set(document["services"]) == {"db", "migrate", "api", "prometheus"}
    assert "pgdata" in document["volumes"]
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
    for name in ("migrate", "api"):
        env = services[name]["environment"]
        assert set(env) <= known, set(env) - known
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
    reserved = 3 + 1  # PostgreSQL's superuser_reserved_connections, a migrate or keys create
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
    for name in ("migrate", "api"):
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
    api_port = services["api"]["ports"][0].split(":")[-1]
    assert server["static_configs"][0]["targets"] == [f"api:{api_port}"]
    assert server["metrics_path"] == "/metrics"
    assert prometheus["depends_on"]["api"]["condition"] == "service_healthy"
