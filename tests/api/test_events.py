"""The event stream's places: a server process serves at most its cap of listeners."""

import time
from contextlib import ExitStack

import httpx
import pytest

from db import Database
from tests.servers import local_client, serving

EVENTS = "/api/v1/events"
#: The cap the test server gets (``CALSTATION_EVENT_LISTENERS``).
CAP = 2


def _open(stack: ExitStack, client: httpx.Client) -> httpx.Response:
    """An event stream opened: its headers received, its body left unread."""
    return stack.enter_context(client.stream("GET", EVENTS))


@pytest.mark.timeout(120)
def test_a_listener_past_the_cap_gets_503_with_retry_after_until_one_leaves(
    migrated_database: Database, database_url: str
) -> None:
    with (
        serving(database_url, event_listeners=str(CAP)) as base,
        local_client(base, timeout=30) as client,
    ):
        first, rest = ExitStack(), ExitStack()
        with first, rest:
            opened = [_open(first, client)] + [_open(rest, client) for _ in range(CAP - 1)]
            assert [answer.status_code for answer in opened] == [200] * CAP
            refused = client.get(EVENTS)
            assert refused.status_code == 503
            assert refused.headers["retry-after"] == "10"
            assert refused.json() == {
                "detail": f"this server process already serves {CAP} event streams "
                "(CALSTATION_EVENT_LISTENERS): retry later"
            }
            assert client.get("/healthz").status_code == 200  # the other reads go on
            first.close()  # one listener leaves: the server sees it gone and frees its place
            while (again := _open(rest, client)).status_code == 503:
                time.sleep(0.1)
            assert again.status_code == 200
            assert again.headers["content-type"].startswith("text/event-stream")
            assert client.get(EVENTS).status_code == 503  # the place is taken again
        documented = client.get("/openapi.json").json()["paths"][EVENTS]["get"]["responses"]
    assert "Retry-After" in documented["503"]["headers"]
    assert "CALSTATION_EVENT_LISTENERS" in documented["503"]["description"]
