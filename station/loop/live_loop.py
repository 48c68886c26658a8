"""The station's loop around its screen: tick, redraw every so often, until done.

Both the one-port station (:class:`station.loop.app.StationApp`) and the multi-slot fixture
(:class:`station.loop.fixture.app.FixtureApp`) run it: on a terminal the screen is a rich
:class:`~rich.live.Live` display redrawn every :data:`DRAW_EVERY_S`; on anything else
(logs, the demo's stderr) nothing is drawn and the station says its lines instead.
"""

import time
from collections.abc import Callable

from rich.console import Console, RenderableType
from rich.live import Live

#: Seconds between screen refreshes.
DRAW_EVERY_S = 0.1


def run_live(
    console: Console,
    screen: Callable[[], RenderableType],
    tick: Callable[[], None],
    done: Callable[[], bool],
    tick_s: float,
) -> None:
    """Call ``tick`` every ``tick_s`` until ``done()``, drawing ``screen()`` on a terminal."""
    if console.is_terminal:
        with Live(screen(), console=console, auto_refresh=False) as live:
            _loop(lambda: live.update(screen(), refresh=True), tick, done, tick_s)
    else:
        _loop(lambda: None, tick, done, tick_s)


def _loop(
    draw: Callable[[], None], tick: Callable[[], None], done: Callable[[], bool], tick_s: float
) -> None:
    next_draw = 0.0
    while not done():
        tick()
        now = time.monotonic()
        if now >= next_draw:
            draw()
            next_draw = now + DRAW_EVERY_S
        time.sleep(tick_s)
    draw()
