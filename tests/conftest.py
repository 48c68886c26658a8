"""Fixtures shared by the whole suite."""

import fcntl
import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from click.testing import CliRunner as ClickRunner
from hypothesis import settings

from station.cli.main import main

pytest_plugins = ["tests.databases", "tests.servers", "tests.browser"]

# Two sizes of the suite's properties and of its API fuzzing, chosen by HYPOTHESIS_PROFILE:
# ``default`` (``make test``) and ``nightly`` (``make test-nightly``). The heavy
# properties name their nightly size through :func:`examples`; ``default`` runs a
# quarter of it, never fewer than MIN_EXAMPLES, so that each still explores enough
# cases to fail. Properties without a size of their own run Hypothesis' 100 examples by
# default and 400 at night.
# Locally every run explores new examples; CI replays a fixed set, so a submission's
# verdict does not hang on a draw (a failure found locally is shrunk and kept there).
# No example fails for taking long (Hypothesis' default deadline is 200 ms of wall
# clock): how busy the machine is must not decide a test.
PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "default")
NIGHTLY = PROFILE == "nightly"
#: The fewest examples a heavy property runs by default.
MIN_EXAMPLES = 10
settings.register_profile("default", deadline=None)
settings.register_profile("nightly", deadline=None, max_examples=400)
for _name in ("default", "nightly"):
    settings.register_profile(f"{_name}-ci", settings.get_profile(_name), derandomize=True)
settings.load_profile(f"{PROFILE}-ci" if os.environ.get("CI") else PROFILE)


def examples(nightly: int) -> int:
    """``max_examples`` of a heavy property (or of one schemathesis operation): its
    ``nightly`` size in the nightly profile, a quarter of it (at least
    :data:`MIN_EXAMPLES`, at most ``nightly``) otherwise."""
    return nightly if NIGHTLY else min(nightly, max(MIN_EXAMPLES, nightly // 4))


REPO_ROOT = Path(__file__).resolve().parent.parent


def pytest_xdist_auto_num_workers() -> int:
    """``-n auto``: two workers a core. A third of a worker's time goes to waiting on
    the real processes its tests start (servers, stations, Chromium, the simulators at
    their clock): with one worker a core the cores idled that third (2 cores: 522 s of
    wall for 663 s of CPU; with four workers 437 s)."""
    return 2 * (os.cpu_count() or 1)


CliRunner = Callable[..., subprocess.CompletedProcess[str]]


def computed_once(
    tmp_path_factory: pytest.TempPathFactory, name: str, compute: Callable[[], object]
) -> object:
    """``compute()`` (a JSON value) once a run: the first xdist worker to ask computes it
    under a lock, the others read what it wrote (pytest-xdist's pattern for set-up that
    must run once, with ``fcntl``'s lock). Without workers, computed here."""
    if "PYTEST_XDIST_WORKER" not in os.environ:
        return compute()
    shared = tmp_path_factory.getbasetemp().parent  # the run's, shared by its workers
    path = shared / f"{name}.json"
    with open(shared / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not path.exists():
            path.write_text(json.dumps(compute()))
        return json.loads(path.read_text())


@pytest.fixture
def run_cli() -> CliRunner:
    """Run ``calstation ARGS...`` as a real process from this source tree.

    Returns the completed process (text mode); keyword arguments go to
    :func:`subprocess.run` (``input=``, ``timeout=``, ``env=``, ``cwd=``).
    """

    def run(*args: str, **kwargs: object) -> subprocess.CompletedProcess[str]:
        env = dict(kwargs.pop("env", None) or os.environ)  # type: ignore[call-overload]
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO_ROOT), env.get("PYTHONPATH")]))
        kwargs.setdefault("timeout", 120)
        return subprocess.run(  # type: ignore[call-overload, no-any-return]
            [sys.executable, "-m", "station", *args],
            capture_output=True,
            text=True,
            env=env,
            check=False,
            **kwargs,
        )

    return run


@pytest.fixture
def call_cli(monkeypatch: pytest.MonkeyPatch) -> CliRunner:
    """Run ``calstation ARGS...`` in this process, through its real entry point
    (:func:`station.cli.main.main`) under Click's test isolation, for tests of what a
    command computes and says rather than of its process: the interpreter and the
    command's libraries are loaded once per test process, not once per call.

    Answers as :func:`run_cli` does (a completed process: exit status, standard output
    and standard error apart); ``input=``, ``env=`` (the whole environment, as for a
    process) and ``cwd=`` as there.
    """

    def run(
        *args: str,
        input: str | None = None,
        env: dict[str, str] | None = None,
        cwd: Path | str | None = None,
    ) -> subprocess.CompletedProcess[str]:
        environment: dict[str, str | None] = {name: None for name in os.environ}
        environment.update(env or os.environ)
        if cwd is not None:
            monkeypatch.chdir(cwd)
        monkeypatch.setattr(sys, "argv", ["calstation", *args])
        with ClickRunner().isolation(input=input, env=environment) as (stdout, stderr, _):
            try:
                main()
                status = 0
            except SystemExit as stop:
                status = stop.code if isinstance(stop.code, int) else int(stop.code is not None)
            finally:
                sys.stdout.flush()
                sys.stderr.flush()
            output, errors = stdout.getvalue(), stderr.getvalue()
        return subprocess.CompletedProcess(
            ["calstation", *args], status, output.decode(), errors.decode()
        )

    return run
