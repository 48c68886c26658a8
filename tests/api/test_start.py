"""A results server's start loads what its API needs, not what only some answers do.

Each library below is imported where it is first used (the pages, the alert loop's
posts, a migration, a redundant fit, a gyro plot): importing one with the server again
would add its load to every start (docs/benchmarks.md, "Server start (issue 28)").
"""

import json
import os
import subprocess
import sys
from pathlib import Path

from db import open_database
from tests.conftest import REPO_ROOT

#: What a started server has not imported: the page renderer and its Jinja, the alert
#: loop's HTTP client, Alembic (a database at the head is checked without it), scipy and
#: matplotlib.
NOT_AT_START = ("station.report.html", "jinja2", "httpx", "alembic", "scipy", "matplotlib")

#: A server's start in a fresh interpreter: the application made, its start-up run (the
#: database opened and its schema checked, the pools made), then what it imported.
START = f"""
import asyncio, json, sys
from api.main import create_app

async def start() -> None:
    app = create_app()
    async with app.router.lifespan_context(app):
        pass

asyncio.run(start())
print(json.dumps(sorted(
    name for name in sys.modules for lib in {NOT_AT_START!r}
    if name == lib or name.startswith(lib + ".")
)))
"""


def test_a_started_server_has_not_imported_what_only_some_answers_need(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'start.sqlite3'}"
    open_database(url).dispose()  # at the head, as a server finds it after its first start
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
    assert json.loads(result.stdout.splitlines()[-1]) == []
