"""The coverage of ``calstation solve``'s U on units drawn from the datasheet alone.

    python benchmarks/bench_datasheet_coverage.py [UNITS]

``tests/datasheet_units.py`` (:class:`CoupledUnit`, written from the KXM52-1050's
datasheet and nothing of the station's simulator) draws UNITS units (default 1,000) per
model: offsets within ±207 counts of 2048, sensitivities within ±3 % of 819.2 counts/g,
each cross-axis term within ±2 %; the six-parameter model's six poses along ±x, ±y, ±z
and the nine-parameter model's twelve (the six and six between the axes), each held up to
5° off and taken as the mean and spread of 1024 rounded samples of 1.2 counts' noise.
Each unit's pose file is solved by ``calstation solve FILE --model M --json`` (in this
process, through the command's entry point, as the test does); printed per model and
group (offsets, sensitivities): the fraction of truths within ±U (k = 2), the mean
|error|/U (0.40 for a normal error whose U is right) and the 99 % binomial band about
95 % for that many coefficients. Seeds 7 (six) and 8 (nine); the test,
``tests/station/cli/test_solve_datasheet_coverage.py``, draws 150 units a model with
seeds 61 and 62.
"""

import subprocess
import sys
import tempfile
from pathlib import Path

from click.testing import CliRunner as ClickRunner

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the datasheet units live with the tests
from station.cli.main import main  # noqa: E402
from tests.station.cli.test_solve_datasheet_coverage import band, coverage  # noqa: E402


def calstation(*args: str) -> subprocess.CompletedProcess[str]:
    """``calstation ARGS`` through its entry point, in this process."""
    sys.argv = ["calstation", *args]
    with ClickRunner().isolation() as (stdout, stderr, _):
        try:
            main()
            status = 0
        except SystemExit as exc:
            status = exc.code if isinstance(exc.code, int) else 1
        return subprocess.CompletedProcess(
            list(args), status, stdout.getvalue().decode(), stderr.getvalue().decode()
        )


def run() -> None:
    units = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    for model, seed in (("six", 7), ("nine", 8)):
        with tempfile.TemporaryDirectory() as tmp:
            measured = coverage(calstation, model, units, seed, Path(tmp))
        low, high = band(measured.count)
        for group, fraction in measured.within.items():
            print(
                f"{model:4s} {group:11s} within ±U {fraction:.1%} of {measured.count}, "
                f"mean |e|/U {measured.error_over_u[group]:.2f}, band {low:.1%}–{high:.1%}"
            )


if __name__ == "__main__":
    run()
