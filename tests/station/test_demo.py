"""``calstation demo``: the README's main command, end to end on virtual putters."""

import json
import os
import sqlite3
from pathlib import Path

import numpy as np

from tests.conftest import CliRunner


def test_demo_json_estimates_land_on_the_truth(run_cli: CliRunner, tmp_path: Path) -> None:
    env_dir = tmp_path / "data"
    env = {**os.environ, "CALSTATION_DATA_DIR": str(env_dir)}
    env.pop("CALSTATION_DATABASE_URL", None)
    result = run_cli("demo", "--units", "2", "--json", "--speed", "20", env=env, timeout=180)
    assert result.returncode == 0, result.stderr
    units = json.loads(result.stdout)  # stdout holds only the JSON
    assert [u["serial"] for u in units] == ["PT001001", "PT001002"]
    for unit in units:
        assert unit["verdict"] == "pass", unit["failures"]
        truth, estimate = unit["truth"], unit["estimate"]
        for axis in "xyz":
            assert abs(estimate["offset"][axis] - truth["offset"][axis]) < 1.0
            ratio = estimate["sensitivity"][axis] / truth["sensitivity"][axis]
            assert abs(ratio - 1) < 1e-3
    assert "PASS" in result.stderr  # the screens went to stderr
    with sqlite3.connect(env_dir / "calstation.sqlite3") as db:
        stored = db.execute("select run_id, verdict, lot from runs order by started_at").fetchall()
    assert [(u["run_id"].replace("-", ""), u["verdict"], "demo-lot") for u in units] == [
        (run_id.replace("-", ""), verdict, lot) for run_id, verdict, lot in stored
    ]
    assert np.isfinite([u["estimate"]["offset"]["x"] for u in units]).all()
