"""The report pool: heavy key-less reads in processes and on connections of their own.

The end-of-line report and the dashboard need no key and cost far more than a
submission (their SQL adds up roll-ups; building and rendering the answer is Python
work, about a second for a 100,000-run range). Run on the submission pool in the event
loop, 60 readers took the stations from 24 submissions/s to 0.23. Here each server
process hands them to ``processes`` report processes, each with one connection of its
own and a lower scheduling priority (:data:`REPORT_NICENESS`): the event loop never
runs their Python (a thread would share the interpreter lock with it), and the
processor goes to the stations first. A request that finds every report process busy
for ``wait_s`` is answered 503 (:class:`ReportsBusyError`); each statement is bounded by
the read timeout (:mod:`db.timeouts`, :class:`ReadTimeoutError`).
"""

import asyncio
import multiprocessing
import os
import threading
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from functools import partial
from typing import TYPE_CHECKING, Any, Concatenate, ParamSpec, TypeVar

from sqlalchemy import Engine
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session

from db import DatabaseUnavailableError, RunRepository, make_engine
from db.timeouts import is_statement_timeout
from station.domain.errors import CalstationError

if TYPE_CHECKING:  # a report process imports this module: FastAPI's metrics stay out of it
    from api.metrics import ServerMetrics

P = ParamSpec("P")
T = TypeVar("T")

#: Niceness of the report processes: under load the processor serves the stations first.
REPORT_NICENESS = 10


class ReportsBusyError(CalstationError):
    """Every report process stayed busy for as long as a request may wait."""


class ReadTimeoutError(CalstationError):
    """A statement of a read ran longer than the read timeout and was ended."""


#: The report process's engine (one connection), made by :func:`_start`.
_engine: Engine | None = None


#: How often a report process looks whether its server process is still there.
PARENT_CHECK_S = 1.0


def _start(url: str, timeout_s: float, engine_options: dict[str, Any] | None, server: int) -> None:
    """Make the report process's engine; end the process once ``server`` (the server
    process's pid, taken before it started this one) is gone. The pid is handed in, not
    read here: a server killed while this process started has already left it to init."""
    global _engine
    os.nice(REPORT_NICENESS)
    _engine = make_engine(
        url, statement_timeout_s=timeout_s, pool_size=1, max_overflow=0, **(engine_options or {})
    )
    threading.Thread(target=_end_with, args=(server,), daemon=True).start()


def _end_with(parent: int) -> None:
    """End this report process once its server process is gone, however that ended."""
    while os.getppid() == parent:
        time.sleep(PARENT_CHECK_S)
    os._exit(0)


def _in_transaction(
    work: Callable[Concatenate[RunRepository, P], T], *args: P.args, **kwargs: P.kwargs
) -> T:
    """``work`` in the report process, in a transaction (the report uses ``SET LOCAL``).

    Database errors cross back to the server process as the product's own errors.
    """
    assert _engine is not None, "report process not started"
    try:
        with Session(_engine) as session, session.begin():
            return work(RunRepository(session), *args, **kwargs)
    except OperationalError as exc:
        if is_statement_timeout(exc):
            raise ReadTimeoutError("statement timeout") from None
        raise DatabaseUnavailableError.of(_engine.url, exc) from None


class ReportPool:
    """``processes`` report processes on the database at ``url`` (their engines made with
    ``engine_options`` too); ``metrics`` shows how busy they are (processes, busy,
    waiting, refused)."""

    def __init__(
        self,
        url: str,
        *,
        processes: int,
        wait_s: float,
        timeout_s: float,
        metrics: "ServerMetrics",
        engine_options: dict[str, Any] | None = None,
    ) -> None:
        self.wait_s = wait_s
        self._metrics = metrics
        metrics.report_processes.set(processes)
        self._free = asyncio.Semaphore(processes)
        self._executor = ProcessPoolExecutor(
            processes,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_start,
            initargs=(url, timeout_s, engine_options, os.getpid()),
        )

    async def run(
        self, work: Callable[Concatenate[RunRepository, P], T], *args: P.args, **kwargs: P.kwargs
    ) -> T:
        """``work(repository, *args)`` in a report process; ``work`` is a module's function,
        which the report process imports (:mod:`api.report_bodies`: no web framework)."""
        metrics = self._metrics
        metrics.report_waiting.inc()
        try:
            async with asyncio.timeout(self.wait_s):
                await self._free.acquire()
        except TimeoutError:
            metrics.reports_busy_refused.inc()
            raise ReportsBusyError(
                f"every report connection stayed busy for {self.wait_s:g} s: retry later"
            ) from None
        finally:
            metrics.report_waiting.dec()
        metrics.report_busy.inc()
        try:
            future = self._executor.submit(partial(_in_transaction, work, *args, **kwargs))
            return await asyncio.wrap_future(future)
        finally:
            metrics.report_busy.dec()
            self._free.release()

    def close(self) -> None:
        """Stop the report processes (a report still running ends on its own)."""
        self._executor.shutdown(wait=False, cancel_futures=True)
        self._metrics.report_processes.set(0)
