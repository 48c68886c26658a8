"""The report pool: heavy key-less reads on connections and threads of their own.

The end-of-line report and the dashboard need no key and cost far more than a
submission (their SQL adds up roll-ups; building and rendering the answer is Python
work). Run on the submission pool, or in the event loop's thread, 60 readers took the
stations from 24 submissions/s to 0.23. Here they run in :attr:`ReportPool.threads`
worker threads (so the event loop keeps answering the stations between two of their
steps), each on its own connection of a pool that nothing else uses, at most that many
at once per server process. A request that finds every report thread busy for
``wait_s`` is answered 503 (:class:`ReportsBusyError`); each statement is bounded by the
engine's statement timeout (:mod:`db.timeouts`).
"""

import asyncio
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

from sqlalchemy import Engine
from sqlalchemy.orm import Session

from db import RunRepository
from station.errors import CalstationError

T = TypeVar("T")


#: Niceness of the report threads (Linux schedules threads apart): under load the
#: processor goes to the event loops, and the stations they serve, first.
REPORT_NICENESS = 10


def _yield_to_the_stations() -> None:
    os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), REPORT_NICENESS)


class ReportsBusyError(CalstationError):
    """Every report connection stayed busy for as long as a request may wait."""


class ReportPool:
    """``threads`` worker threads, each with a connection of ``engine`` (sized alike)."""

    def __init__(self, engine: Engine, *, threads: int, wait_s: float) -> None:
        self.engine = engine
        self.threads = threads
        self.wait_s = wait_s
        self._free = asyncio.Semaphore(threads)
        self._executor = ThreadPoolExecutor(
            threads, thread_name_prefix="report", initializer=_yield_to_the_stations
        )

    async def run(self, work: Callable[[RunRepository], T]) -> T:
        """``work(repository)`` in a report thread, in a transaction of its own.

        A transaction: the report sets its PostgreSQL planner options with ``SET LOCAL``.
        """
        try:
            async with asyncio.timeout(self.wait_s):
                await self._free.acquire()
        except TimeoutError:
            raise ReportsBusyError(
                f"every report connection stayed busy for {self.wait_s:g} s: retry later"
            ) from None
        try:
            loop = asyncio.get_running_loop()
            return await loop.run_in_executor(self._executor, self._in_transaction, work)
        finally:
            self._free.release()

    def _in_transaction(self, work: Callable[[RunRepository], T]) -> T:
        with Session(self.engine) as session, session.begin():
            return work(RunRepository(session))

    def close(self) -> None:
        """Stop the threads (a report still running ends on its own) and the connections."""
        self._executor.shutdown(wait=False, cancel_futures=True)
        self.engine.dispose()
