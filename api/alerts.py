"""The alert loop of a server process: the plant's rules checked, their alerts posted.

Every ``interval`` the rules are evaluated against the stored runs and the due alerts
posted to the webhook as JSON (httpx) (:mod:`db.report.alerts`: stored once per event, held by
one process while it posts). A webhook that does not answer 2xx, or not at all, gets the
alert again after the retry interval; it is never stored twice. Any number of server
processes may run the loop at once.
"""

import asyncio
import logging
from datetime import UTC, datetime, timedelta
from typing import TYPE_CHECKING

from sqlalchemy.ext.asyncio import AsyncSession, async_sessionmaker

from db.report import claim_next, evaluate, mark_delivered, retry_later
from station.domain.quality.alerts import AlertRules

# httpx is imported by the loop when it runs: a server without alert rules never posts, and
# the import (with httpx's command line: click, rich, pygments) costs ~0.1 s of every start.
if TYPE_CHECKING:
    import httpx

log = logging.getLogger(__name__)

#: The longest a webhook may take to answer a post (each of connecting, sending and
#: reading the answer).
POST_TIMEOUT_S = 10.0
#: How long a claimed alert is this process's: longer than the longest post (the three
#: phases and the pool), so no other process posts it meanwhile.
CLAIM_HOLD = timedelta(seconds=6 * POST_TIMEOUT_S)


class AlertLoop:
    """Evaluates ``rules`` and posts their alerts every ``interval_s``; ``rounds``: the
    rounds done (the alerts page shows it: a reader sees the loop going)."""

    def __init__(
        self,
        sessions: async_sessionmaker[AsyncSession],
        rules: AlertRules,
        interval_s: float,
        retry_s: float,
    ) -> None:
        self.sessions = sessions
        self.rules = rules
        self.interval_s = interval_s
        self.retry = timedelta(seconds=retry_s)
        self.rounds = 0

    async def run(self) -> None:
        """Rounds until cancelled; a round that fails (the database away) is logged and
        the next one tries again."""
        import httpx

        async with httpx.AsyncClient(timeout=POST_TIMEOUT_S) as client:
            while True:
                try:
                    await self.round(client)
                except Exception:  # the loop outlives a database or network fault
                    log.exception("alert round failed; the next one tries again")
                await asyncio.sleep(self.interval_s)

    async def round(self, client: "httpx.AsyncClient") -> None:
        """Evaluate the rules, then post each alert due at the round's start, one at a
        time: claimed (held for :data:`CLAIM_HOLD`) just before its post, so a slow
        webhook never lets another process claim and post it too."""
        import httpx

        start = datetime.now(UTC)
        async with self.sessions() as session, session.begin():
            await session.run_sync(evaluate, self.rules, start)
        while True:
            async with self.sessions() as session, session.begin():
                alert = await session.run_sync(claim_next, start, datetime.now(UTC), CLAIM_HOLD)
            if alert is None:
                break
            try:
                answer = await client.post(
                    str(self.rules.webhook), json=alert.model_dump(mode="json")
                )
                taken = answer.is_success
            except httpx.HTTPError as exc:
                log.warning("webhook did not take alert %s: %s", alert.event_key, exc)
                taken = False
            now = datetime.now(UTC)
            async with self.sessions() as session, session.begin():
                if taken:
                    await session.run_sync(mark_delivered, alert.event_key, now)
                else:
                    await session.run_sync(retry_later, alert.event_key, now + self.retry)
        self.rounds += 1
