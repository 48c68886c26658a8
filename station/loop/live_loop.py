"""The station's loop around its screen, shared by both front-ends.

:class:`FrontEnd` is what the one-port station (:class:`station.loop.app.StationApp`) and
the multi-slot fixture (:class:`station.loop.fixture.app.FixtureApp`) have in common: their
slots and the unit lifecycle behind them (:class:`station.loop.lifecycle.UnitLifecycle`),
the keys they read, the console they draw on, and the loop: tick, redraw every so often,
until done. On a terminal the screen is a rich :class:`~rich.live.Live` display redrawn
after every pass; on anything else (logs, the demo's stderr) nothing is drawn and the
station says its lines instead.
"""

import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence

from rich.console import Console, RenderableType
from rich.live import Live
from rich.text import Text

from station.domain.errors import InputError
from station.domain.i18n import tr, trn
from station.domain.product.limits import LimitsProfile
from station.domain.record.records import RunRecord
from station.loop.config import StationConfig
from station.loop.keyboard import KeySource
from station.loop.lifecycle import UnitLifecycle
from station.loop.screens import header
from station.loop.slot import Slot
from station.results.rescue import Rescued
from station.results.storage import RunStore

#: Seconds between the loop's passes (keys, units, outbox, then the screen redrawn): the
#: four redraws a second of rich's own ``Live`` default, within the live view's window
#: (:data:`station.run.capture.LIVE_SAMPLES`, 0.256 s at 500 samples/s), so that a pass
#: on time judges one window. A key ends the wait at once (:meth:`KeySource.wait`), so
#: typing is echoed without delay. Every pass more burns the station's CPU for nothing:
#: each wake costs about half a millisecond whatever it carries, and the pass
#: reads the putter's port itself (:meth:`station.device.link.PutterLink.read_now`). A
#: capture's window is judged on its samples' sequence numbers, so its device time does
#: not depend on when a pass comes.
TICK_S = 0.25


class FrontEnd(ABC):
    """A station's front-end: its slots, keys and console, served until done.

    ``units``: stop once that many runs are recorded; ``probe_ports``: try the putter
    ports at start (the demo's ports exist only while a unit is in).
    """

    def __init__(
        self,
        *,
        config: StationConfig,
        profile: LimitsProfile,
        slots: Sequence[Slot],
        open_store: Callable[[], RunStore],
        keys: KeySource,
        console: Console,
        units: int | None = None,
        tick_s: float = TICK_S,
        probe_ports: bool = True,
    ) -> None:
        self.config = config
        self.profile = profile
        self.keys = keys
        self.console = console
        self.units = units
        self.tick_s = tick_s
        self.probe_ports = probe_ports
        self.lifecycle = UnitLifecycle(
            config=config,
            profile=profile,
            slots=slots,
            open_store=open_store,
            say_line=self._say_line,
        )
        self.results = self.lifecycle.results
        self.done = False
        #: Asked to stop with runs only in memory: one more sync first, then a warning;
        #: asked again, they are rescued (:mod:`station.results.rescue`).
        self._stopping = False
        self._warned = False
        #: Where what only the memory held went when the station stopped (None: nothing).
        self.rescued: Rescued | None = None

    @property
    def records(self) -> list[RunRecord]:
        """Every run recorded since the station started."""
        return self.lifecycle.records

    def serve(self) -> list[RunRecord]:
        """Serve units until the keys end, ``quit`` is typed or ``units`` are done."""
        self._say_line(f"calstation {self.lifecycle.versions}{self._title()}")
        stop_metrics = self._serve_metrics()
        self.lifecycle.open_results()
        for line in [*self._port_lines(), *self.lifecycle.checks.lines()]:
            self._say_line(line)
        self._begin()
        try:
            if self.console.is_terminal:
                with Live(self.screen(), console=self.console, auto_refresh=False) as live:
                    self._loop(lambda: live.update(self.screen(), refresh=True))
            else:
                self._loop(lambda: None)
        finally:
            self.lifecycle.close()
            self.rescued = self.results.rescue()
            stop_metrics()
        return self.records

    def stopped_line(self) -> str:
        """What a station stopped by Ctrl-C says it left: the journal of each unit in
        progress, kept on disk, which the station offers to resume when it starts again."""
        kept = [slot.run.journal for slot in self.lifecycle.running if slot.run is not None]
        if not kept:
            return tr("stopped (Ctrl-C): no unit was in progress")
        if len(kept) == 1:
            journal = kept[0]
            return tr(
                "stopped (Ctrl-C): the journal of unit {serial} is kept at pose {number} of "
                "{total}: the station offers to resume it when it starts again",
                serial=journal.serial,
                number=journal.next_pose + 1,
                total=len(journal.poses),
            )
        return tr(
            "stopped (Ctrl-C): the journals of units {serials} are kept: the station offers "
            "to resume them when it starts again",
            serials=", ".join(journal.serial for journal in kept),
        )

    def _serve_metrics(self) -> Callable[[], None]:
        """Serve the station's metrics on its ``metrics_port``, if it has one; returns
        what stops them."""
        port = self.config.metrics_port
        if port is None:
            return lambda: None
        from station.loop.metrics import serve_metrics  # prometheus-client only when asked

        try:
            stop = serve_metrics(self, port, self.config.metrics_host)
        except OSError as exc:
            raise InputError(
                f"metrics_port {port}: cannot listen on {self.config.metrics_host}:{port} "
                f"({exc.strerror or exc})"
            ) from None
        self._say_line(
            tr("metrics: {url}", url=f"http://{self.config.metrics_host}:{port}/metrics")
        )
        return stop

    def _stop(self) -> None:
        """``quit`` or Ctrl-D: stop, unless runs are only in memory. Then one more sync is
        tried, and if it cannot take them the operator is told where they are and what to
        do; asked again, the station stops and saves them anywhere it can."""
        runs, journals = self.results.in_memory()
        if not (runs or journals) or self._warned:
            self.done = True
        elif not self._stopping:
            self._stopping = True
            self.results.sync()

    def _stopping_tick(self) -> None:
        """Once the last sync before stopping is done: stop, or say what is held."""
        if not self._stopping or self.results.syncing:
            return
        self._stopping = False
        runs, journals = self.results.in_memory()
        if not (runs or journals):
            self.done = True
            return
        self._warned = True
        held = tr(" and ").join(
            part
            for part in (
                trn("{count} finished run", "{count} finished runs", runs) if runs else "",
                trn("{count} unit journal", "{count} unit journals", journals) if journals else "",
            )
            if part
        )
        self._tell(
            tr(
                "NOT STOPPED: {held} only in memory (the disk refuses them, the results store "
                "does not take them): free the disk or bring the store back and they go; quit "
                "or Ctrl-D again to save them elsewhere and stop",
                held=held,
            )
        )

    def _loop(self, draw: Callable[[], None]) -> None:
        """Pass, redraw, wait for a key or the next pass. Passes keep their cadence (a
        pass a key brings in between does not move the next one), so a pass drains a
        tick's samples, within one live window (:data:`TICK_S`); one that falls behind
        is followed a whole tick later, never by a burst."""
        due = time.monotonic()
        while not self.done:
            self.tick()
            draw()
            now = time.monotonic()
            if now >= due:
                due += self.tick_s
                if due <= now:
                    due = now + self.tick_s
            self.keys.wait(due - now)
        draw()

    def top(self) -> list[RenderableType]:
        """The top of the screen: who, the outbox, versions, the store and the disk, the
        station's own checks."""
        results = self.results
        return [
            header(
                self.config.station_id,
                self.config.operator_id,
                self.lifecycle.versions,
                results.backlog,
                results.set_aside,
            ),
            *results.status_lines(),
            *(Text(line, style="bold red") for line in self.lifecycle.checks.lines()),
        ]

    def _say_line(self, text: str) -> None:
        """A line for a console that is not a terminal (logs, the demo's stderr)."""
        if not self.console.is_terminal:
            self.console.print(text, markup=False, highlight=False, soft_wrap=True)

    def _title(self) -> str:
        """What follows the versions in the first line said."""
        return ""

    @abstractmethod
    def _tell(self, note: str) -> None:
        """Show ``note`` on the screen, and log it."""

    @property
    @abstractmethod
    def last_note(self) -> str | None:
        """The note shown last (what the station last told the operator)."""

    @abstractmethod
    def _port_lines(self) -> list[str]:
        """Lines about the putter ports at start (none when not probed)."""

    @abstractmethod
    def _begin(self) -> None:
        """What the front-end does before its first tick (offer an interrupted run)."""

    @abstractmethod
    def tick(self) -> None:
        """One pass: keys, the units in progress, the outbox."""

    @abstractmethod
    def screen(self) -> RenderableType:
        """The whole screen as it stands."""
