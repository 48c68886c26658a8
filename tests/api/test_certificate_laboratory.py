"""The laboratory a results server's certificates name (``CALSTATION_LABORATORY_FILE``),
over a real server, and a laboratory file it cannot use stopping it at start."""

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from db import Database, RunRepository
from tests.conftest import CliRunner
from tests.db.records import make_record
from tests.servers import local_client, serving

LABORATORY = """[laboratory]
name = "Putter Works Calibration Lab"
address = "12 Gangnam-daero, Seoul"
customer = "Putter Works Quality"
gravity_m_s2 = 9.79966
traceability = "g from the plant's absolute gravity survey"
"""


@pytest.fixture
def lab_url(database: Database, database_url: str, tmp_path: Path) -> Iterator[str]:
    """A server naming ``LABORATORY`` on its certificates."""
    path = tmp_path / "laboratory.toml"
    path.write_text(LABORATORY)
    with serving(database_url, laboratory_file=str(path)) as base:
        yield base


def test_the_server_s_certificate_names_its_configured_laboratory(
    database: Database, lab_url: str
) -> None:
    with database.session() as session:
        RunRepository(session).submit(make_record(serial="U7"))
        session.commit()
    with local_client(lab_url) as client:
        page = client.get("/api/v1/units/U7/certificate").text
    assert '<td class="laboratory">Putter Works Calibration Lab</td>' in page
    assert '<td class="customer">Putter Works Quality</td>' in page
    # Where: no location configured, so the address, and the run's station.
    assert '<td class="location">12 Gangnam-daero, Seoul, station line1-st1</td>' in page
    assert "g = 9.79966 m/s²" in page


@pytest.mark.parametrize(
    ("content", "named"),
    [
        (None, "cannot read the laboratory"),
        ('name = "Lab"\n', "no [laboratory] table"),
        ("[laboratory]\ncustomer = 7\n", "customer: Input should be a valid string"),
    ],
)
def test_an_unusable_laboratory_file_stops_the_server_with_one_line(
    run_cli: CliRunner, tmp_path: Path, content: str | None, named: str
) -> None:
    path = tmp_path / "laboratory.toml"
    if content is not None:
        path.write_text(content)
    clean = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    env = {**clean, "CALSTATION_DATA_DIR": str(tmp_path), "CALSTATION_LABORATORY_FILE": str(path)}
    result = run_cli("serve", "--port", "1", env=env)
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith(f"calstation: error: CALSTATION_LABORATORY_FILE: {path}: ")
    assert named in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
