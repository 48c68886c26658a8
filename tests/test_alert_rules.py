"""deploy/prometheus/: the alert rules and scrape configuration parse, and every metric
they name is one the server or a station exports (``promtool`` checks them too where it
is installed)."""

import re
import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import yaml
from prometheus_client.registry import Collector

from api.metrics import ServerMetrics
from station.loop.metrics import StationCollector
from station.results.outbox import Outbox
from tests.conftest import REPO_ROOT

DEPLOY = REPO_ROOT / "deploy" / "prometheus"
RULES = DEPLOY / "alerts.yml"
CONFIG = DEPLOY / "prometheus.yml"
#: A metric name in a PromQL expression (ours all start so).
METRIC = re.compile(r"\bcalstation_[a-z0-9_]+")
#: The sample names a family of each type exposes.
SUFFIXES = {
    "counter": ("_total", "_created"),
    "gauge": ("",),
    "histogram": ("_bucket", "_count", "_sum", "_created"),
}


def _sample_names(collector: Collector) -> set[str]:
    return {
        f"{family.name}{suffix}"
        for family in collector.collect()
        for suffix in SUFFIXES[family.type]
    }


def _exported(tmp_path: Path) -> set[str]:
    """Every sample name the server's metrics and a station's can carry."""
    server = _sample_names(ServerMetrics().registry)
    results = SimpleNamespace(
        outbox=Outbox(tmp_path / "outbox"),
        disk_note=None,
        disk=SimpleNamespace(data_dir=tmp_path),
    )
    station: Any = SimpleNamespace(
        config=SimpleNamespace(station_id="st-1"), results=results, records=[]
    )
    return server | _sample_names(StationCollector(station))


def _rules() -> list[dict[str, Any]]:
    document = yaml.safe_load(RULES.read_text())
    return [rule for group in document["groups"] for rule in group["rules"]]


def test_every_rule_names_only_metrics_that_are_exported(tmp_path: Path) -> None:
    exported = _exported(tmp_path)
    rules = _rules()
    named = {name for rule in rules for name in METRIC.findall(rule["expr"])}
    assert named, "no rule names a calstation metric"
    assert named - exported == set()


def test_the_plant_starts_with_the_alerts_the_issue_asks_for() -> None:
    alerts = {rule["alert"]: rule for rule in _rules()}
    assert {
        "CalstationOutboxGrowing",
        "CalstationYieldDropping",
        "CalstationNoRunsFromStation",
    } <= (set(alerts))
    assert "calstation_station_outbox_runs" in alerts["CalstationOutboxGrowing"]["expr"]
    assert "[1h]" in alerts["CalstationNoRunsFromStation"]["expr"]
    for rule in alerts.values():
        assert rule["annotations"]["summary"]
        assert rule["labels"]["severity"] in {"warning", "critical"}


def test_the_scrape_configuration_loads_the_rules() -> None:
    config = yaml.safe_load(CONFIG.read_text())
    assert config["rule_files"] == [f"/etc/prometheus/{RULES.name}"]
    jobs = {job["job_name"] for job in config["scrape_configs"]}
    assert jobs == {"calstation-server", "calstation-stations"}


def test_promtool_accepts_the_rules_and_the_configuration(tmp_path: Path) -> None:
    promtool = shutil.which("promtool")
    if promtool is None:
        pytest.skip("promtool is not installed (the rules are checked as YAML above)")
    checked = subprocess.run(
        [promtool, "check", "rules", str(RULES)], capture_output=True, text=True, timeout=60
    )
    assert checked.returncode == 0, checked.stdout + checked.stderr
    # The configuration names the rules where the container mounts them: check a copy.
    (tmp_path / RULES.name).write_text(RULES.read_text())
    config = CONFIG.read_text().replace("/etc/prometheus/", f"{tmp_path}/")
    (tmp_path / CONFIG.name).write_text(config)
    checked = subprocess.run(
        [promtool, "check", "config", str(tmp_path / CONFIG.name)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert checked.returncode == 0, checked.stdout + checked.stderr
