"""Fixtures shared by the whole suite."""

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import settings

pytest_plugins = ["tests.databases", "tests.servers", "tests.browser"]

# Locally every run explores new examples; CI replays a fixed set, so a submission's
# verdict does not hang on a draw (a failure found locally is shrunk and kept there).
# No example fails for taking long (Hypothesis' default deadline is 200 ms of wall
# clock): how busy the machine is must not decide a test.
settings.register_profile("local", deadline=None)
settings.register_profile("ci", settings.get_profile("local"), derandomize=True)
settings.load_profile("ci" if os.environ.get("CI") else "local")

REPO_ROOT = Path(__file__).resolve().parent.parent

CliRunner = Callable[..., subprocess.CompletedProcess[str]]


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
