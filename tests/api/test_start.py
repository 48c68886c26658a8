"""A results server's start loads what its API needs, not what only some answers do.

Each library below is imported where it is first used (the pages, the alert loop's
posts, a migration, a redundant fit, a gyro plot): importing one with the server again
would add its load to every start (docs/benchmarks.md, "Server start").
``calstation serve`` holds the garbage collector off while the server loads; the
application's start-up turns it back on.
"""

import json
import os
import subprocess
import sys
from typing import Any

import pytest

from db import open_database
from tests.conftest import REPO_ROOT

#: What a started server has not imported: the page renderer and its Jinja, the alert
#: loop's HTTP client, Alembic (a database at the head is checked without it), scipy and
#: matplotlib.
NOT_AT_START = ("station.report.html", "jinja2", "httpx", "alembic", "scipy", "matplotlib")

#: A server's start in a fresh interpreter, the collector off as ``calstation serve``
#: leaves it: the application made, its start-up run (the database opened and its schema
#: checked, the pools made); then what it imported and whether the collector is on.
START = f"""
import asyncio, gc, json, sys
gc.disable()
from api.main import create_app

async def start() -> bool:
    app = create_app()
    async with app.router.lifespan_context(app):
        return gc.isenabled()

collector_on = asyncio.run(start())
imported = sorted(
    name for name in sys.modules for lib in {NOT_AT_START!r}
    if name == lib or name.startswith(lib + ".")
)
print(json.dumps({{"imported": imported, "collector_on": collector_on}}))
"""


@pytest.fixture(scope="module")
def started(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """What :data:`START` reports, on a database at the head (as a server finds it
    after its first start)."""
    url = f"sqlite:///{tmp_path_factory.mktemp('start') / 'start.sqlite3'}"
    open_database(url).dispose()
    env = {**os.environ, "PYTHONPATH": str(REPO_ROOT), "CALSTATION_DATABASE_URL": url}
    result = subprocess.run(
        [sys.executable, "-c", START],
        capture_output=True,
        text=True,
        env=env,
        check=False,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    answer: dict[str, Any] = json.loads(result.stdout.splitlines()[-1])
    return answer


def test_a_started_server_has_not_imported_what_only_some_answers_need(
    started: dict[str, Any],
) -> None:
    assert started["imported"] == []


def test_the_start_up_turns_the_collector_back_on(started: dict[str, Any]) -> None:
    assert started["collector_on"] is True
