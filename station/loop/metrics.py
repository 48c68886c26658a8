"""The station's own Prometheus metrics, served on ``metrics_port`` while it runs.

:class:`StationCollector` reads the station as it stands at each scrape (nothing is
counted twice, nothing kept beside what the station keeps anyway): the outbox (runs
waiting, the oldest one's age, files set aside), the units recorded since start by
verdict, their cycle time (scan to verdict), the serial link's losses in their poses,
and the data disk (writes refused, free bytes). :func:`serve_metrics` serves them with
prometheus-client's own HTTP server, in a thread beside the loop; the station's
configuration turns it on (``metrics_port``, off by default; ``metrics_host``).
"""

import shutil
import time
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

from prometheus_client import CollectorRegistry, start_http_server
from prometheus_client.core import (
    CounterMetricFamily,
    GaugeMetricFamily,
    HistogramMetricFamily,
    Metric,
)
from prometheus_client.registry import Collector

from station.domain.record.records import LinkStats

if TYPE_CHECKING:
    from station.loop.live_loop import FrontEnd

#: Cycle-time buckets (seconds from start to verdict): a unit takes one to a few minutes.
CYCLE_BUCKETS = (30.0, 45.0, 60.0, 90.0, 120.0, 180.0, 300.0, 600.0)


class StationCollector(Collector):
    """The metrics of ``station`` (a one-port station or a fixture), read at each scrape."""

    def __init__(self, station: "FrontEnd", clock: Callable[[], float] = time.time) -> None:
        self.station = station
        self.clock = clock

    def collect(self) -> Iterator[Metric]:
        station = self.station
        results = station.results
        outbox = results.outbox
        labels, name = ["station"], [station.config.station_id]

        waiting = GaugeMetricFamily(
            "calstation_station_outbox_runs",
            "Runs waiting in the outbox to be stored",
            labels=labels,
        )
        waiting.add_metric(name, outbox.count())
        yield waiting
        oldest = GaugeMetricFamily(
            "calstation_station_outbox_oldest_age_seconds",
            "Seconds the oldest run in the outbox has waited (0: none waits)",
            labels=labels,
        )
        oldest.add_metric(name, outbox.oldest_age_s(self.clock()))
        yield oldest
        aside = GaugeMetricFamily(
            "calstation_station_outbox_set_aside",
            "Outbox files set aside (unreadable, or refused by the results store)",
            labels=[*labels, "kind"],
        )
        for kind, count in zip(("unreadable", "refused"), outbox.set_aside(), strict=True):
            aside.add_metric([*name, kind], count)
        yield aside

        records = list(station.records)  # the loop appends; a copy to read
        units = CounterMetricFamily(
            "calstation_station_units",
            "Units recorded since the station started, by verdict (golden: its check)",
            labels=[*labels, "verdict", "purpose"],
        )
        tally: dict[tuple[str, str], int] = {}
        for record in records:
            key = (record.verdict, record.purpose or "production")
            tally[key] = tally.get(key, 0) + 1
        for (verdict, purpose), count in sorted(tally.items()):
            units.add_metric([*name, verdict, purpose], count)
        yield units

        cycles = [(r.finished_at - r.started_at).total_seconds() for r in records]
        buckets = [(f"{bound:g}", sum(1 for c in cycles if c <= bound)) for bound in CYCLE_BUCKETS]
        cycle = HistogramMetricFamily(
            "calstation_station_cycle_seconds",
            "Seconds from a unit's start to its verdict",
            labels=labels,
        )
        cycle.add_metric(name, [*buckets, ("+Inf", len(cycles))], sum_value=sum(cycles))
        yield cycle

        link = CounterMetricFamily(
            "calstation_station_link_losses",
            "Serial link losses in the recorded units' poses, by kind",
            labels=[*labels, "kind"],
        )
        for kind in LinkStats.model_fields:
            total = sum(getattr(pose.link, kind) for r in records for pose in r.poses)
            link.add_metric([*name, kind], total)
        yield link

        refused = GaugeMetricFamily(
            "calstation_station_disk_refusing_writes",
            "1 while the data disk refuses writes (runs or journals only in memory)",
            labels=labels,
        )
        refused.add_metric(name, int(results.disk_note is not None))
        yield refused
        try:
            free = float(shutil.disk_usage(results.disk.data_dir).free)
        except OSError:
            return  # no directory, no free space to tell
        space = GaugeMetricFamily(
            "calstation_station_disk_free_bytes", "Free bytes on the data disk", labels=labels
        )
        space.add_metric(name, free)
        yield space


def serve_metrics(station: "FrontEnd", port: int, host: str) -> Callable[[], None]:
    """Serve ``station``'s metrics on ``host:port`` (``/metrics``, or any path); returns
    what stops the server."""
    registry = CollectorRegistry(auto_describe=False)
    registry.register(StationCollector(station))
    server, thread = start_http_server(port, addr=host, registry=registry)

    def stop() -> None:
        server.shutdown()
        server.server_close()
        thread.join()

    return stop
