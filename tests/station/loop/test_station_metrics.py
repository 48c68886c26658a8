"""A station's own metrics (``metrics_port``): scraped over HTTP while the station runs.

The demo's scripted operator calibrates two virtual putters on a station whose results
store does not answer; when it has no unit left it scrapes the station's metrics (from
the station's loop, while the metrics server answers from its own thread) before it
says it is done.
"""

from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest
from prometheus_client.parser import text_string_to_metric_families
from rich.console import Console

from station.cli.station import _station
from station.domain.errors import InputError
from station.domain.product.limits import load_profile
from station.loop.config import load_config
from station.loop.demo import ScriptedOperator
from tests.servers import free_port, local_get

Samples = dict[tuple[str, tuple[tuple[str, str], ...]], float]


@dataclass
class ScrapingOperator(ScriptedOperator):
    """The demo's operator, who scrapes the station's metrics once every unit is done."""

    metrics_url: str = ""
    scraped: Samples | None = None

    def read(self) -> str:
        try:
            return super().read()
        except EOFError:
            if self.scraped is None:
                text = local_get(self.metrics_url, timeout=10).text
                self.scraped = {
                    (s.name, tuple(sorted(s.labels.items()))): s.value
                    for family in text_string_to_metric_families(text)
                    for s in family.samples
                }
            raise


def _station_config(tmp_path: Path, metrics_port: int) -> dict[str, object]:
    return {
        "station_id": "line1-st7",
        "data_dir": tmp_path / "data",
        "port": str(tmp_path / "putter"),
        # A results server nobody runs: the runs wait in the outbox.
        "server_url": f"http://127.0.0.1:{free_port()}",
        "api_key": "csk_test",
        "metrics_port": metrics_port,
        "metrics_host": "127.0.0.1",
    }


def test_a_station_serves_its_outbox_units_cycle_time_and_disk(tmp_path: Path) -> None:
    port = free_port()
    config = load_config(None, _station_config(tmp_path, port))
    operator = ScrapingOperator(
        units=2,
        port=tmp_path / "putter",
        seed=3,
        speed=20.0,
        metrics_url=f"http://127.0.0.1:{port}/metrics",
    )
    with (tmp_path / "screen.txt").open("w") as screen:
        console = Console(file=screen, force_terminal=False)
        # No unit count: the station goes on until its operator is done (and scraped).
        app = _station(config, load_profile(), operator, console, None, probe_port=False)
        operator.station = app
        try:
            records = app.serve()
        finally:
            operator.close()
    samples = operator.scraped
    assert samples is not None
    assert len(records) == 2

    def value(name: str, **labels: str) -> float:
        key = (name, tuple(sorted({"station": "line1-st7", **labels}.items())))
        return samples[key]

    assert value("calstation_station_outbox_runs") == 2
    assert value("calstation_station_outbox_oldest_age_seconds") >= 0
    verdicts = {r.verdict for r in records}
    for verdict in verdicts:
        expected = sum(r.verdict == verdict for r in records)
        assert value("calstation_station_units_total", verdict=verdict, purpose="production") == (
            expected
        )
    assert value("calstation_station_cycle_seconds_count") == 2
    cycle = sum((r.finished_at - r.started_at).total_seconds() for r in records)
    assert value("calstation_station_cycle_seconds_sum") == pytest.approx(cycle)
    lost = sum(p.link.lost_samples for r in records for p in r.poses)
    assert value("calstation_station_link_losses_total", kind="lost_samples") == lost
    assert value("calstation_station_disk_refusing_writes") == 0
    assert value("calstation_station_disk_free_bytes") > 0
    # The server stopped with the station.
    with pytest.raises(httpx.TransportError):
        local_get(operator.metrics_url, timeout=2)


def test_a_metrics_port_taken_is_one_line(tmp_path: Path) -> None:
    port = free_port()
    config = load_config(None, _station_config(tmp_path, port))
    operator = ScriptedOperator(units=1, port=tmp_path / "putter")
    with (tmp_path / "screen.txt").open("w") as screen:
        console = Console(file=screen, force_terminal=False)
        first = _station(config, load_profile(), operator, console, 1, probe_port=False)
        stop = first._serve_metrics()
        try:
            second = _station(config, load_profile(), operator, console, 1, probe_port=False)
            with pytest.raises(InputError, match=rf"^metrics_port {port}: cannot listen on"):
                second.serve()
        finally:
            stop()


def test_the_metrics_port_is_off_by_default_and_checked() -> None:
    assert load_config(None, {}).metrics_port is None
    with pytest.raises(InputError, match="metrics_port"):
        load_config(None, {"metrics_port": 70000})
