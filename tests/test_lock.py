"""The lock files pin what ``pyproject.toml`` asks for (``make lock-check``, run first by
``.ci/run``; ``make lock`` regenerates them).

``requirements.lock`` (the image) and ``requirements-dev.lock`` (``.venv`` and CI) are
written by ``uv pip compile``: one entry a library, each ``name==version`` with its
hashes, marked ``# via calstation (pyproject.toml)`` when pyproject names it. The lock
is fresh when every library that pyproject names is pinned at a version its range
allows (on every Python the lock forks for), and nothing is pinned as pyproject's own
that pyproject no longer names. The transitive closure is checked by the install
itself: pip's ``--require-hashes`` refuses any library the lock does not pin.
"""

import re
import tomllib
from dataclasses import dataclass

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from tests.conftest import REPO_ROOT

PROJECT = tomllib.loads((REPO_ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
#: Each lock file and the requirements of pyproject it locks.
LOCKS = {
    "requirements.lock": PROJECT["dependencies"],
    "requirements-dev.lock": [
        *PROJECT["dependencies"],
        *PROJECT["optional-dependencies"]["dev"],
    ],
}
#: An entry of a lock file: its requirement line up to the hashes, then its comments.
ENTRY = re.compile(r"^(?P<line>[A-Za-z0-9][^\\\n]*?)\s*\\?\n(?P<body>(?:[ #].*\n?)*)", re.M)
OWN = "calstation (pyproject.toml)"


@dataclass(frozen=True)
class Pin:
    """One entry of a lock file."""

    requirement: Requirement
    #: pyproject.toml names it (``# via calstation (pyproject.toml)``).
    direct: bool

    @property
    def version(self) -> str:
        (specifier,) = self.requirement.specifier
        assert specifier.operator == "==", self.requirement
        return specifier.version


def pins(text: str) -> list[Pin]:
    """The entries of a lock file written by ``uv pip compile --generate-hashes``."""
    found = []
    for entry in ENTRY.finditer(text):
        body = entry["body"]
        assert "--hash=sha256:" in body, f"{entry['line']} has no hash"
        found.append(Pin(Requirement(entry["line"]), OWN in body))
    return found


def problems(wanted: list[str], locked: list[Pin]) -> list[str]:
    """What makes ``locked`` stale against the requirements ``wanted`` (empty: fresh)."""
    requirements = {canonicalize_name(r.name): r for r in map(Requirement, wanted)}
    by_name: dict[str, list[Pin]] = {}
    for pin in locked:
        by_name.setdefault(canonicalize_name(pin.requirement.name), []).append(pin)
    found = []
    for name, requirement in requirements.items():
        if name not in by_name:
            found.append(f"{requirement} is not pinned")
        for pin in by_name.get(name, []):
            if not requirement.specifier.contains(pin.version, prereleases=True):
                found.append(f"{pin.requirement} is outside {requirement}")
    for name, entries in by_name.items():
        if name not in requirements and any(pin.direct for pin in entries):
            found.append(f"{name} is pinned as pyproject's own, which no longer names it")
    return found


@pytest.mark.parametrize("lock", sorted(LOCKS))
def test_the_lock_pins_every_library_pyproject_names_in_its_range(lock: str) -> None:
    locked = pins((REPO_ROOT / lock).read_text(encoding="utf-8"))
    assert len(locked) > len(LOCKS[lock])
    assert problems(LOCKS[lock], locked) == []


def test_the_lock_of_the_image_holds_no_development_tool() -> None:
    image = {p.requirement.name for p in pins((REPO_ROOT / "requirements.lock").read_text())}
    assert {"pytest", "mypy", "ruff", "uv"}.isdisjoint(image)


LOCK_TEXT = """\
fastapi==0.141.0 \\
    --hash=sha256:00 \\
    --hash=sha256:01
    # via calstation (pyproject.toml)
numpy==2.4.6 ; python_full_version < '3.12' \\
    --hash=sha256:02
    # via
    #   calstation (pyproject.toml)
    #   scipy
numpy==2.5.5 ; python_full_version >= '3.12' \\
    --hash=sha256:03
    # via
    #   calstation (pyproject.toml)
    #   scipy
starlette==0.50.0 \\
    --hash=sha256:04
    # via fastapi
"""


def test_a_lock_that_fits_pyproject_is_fresh() -> None:
    locked = pins(LOCK_TEXT)
    assert [p.version for p in locked] == ["0.141.0", "2.4.6", "2.5.5", "0.50.0"]
    assert [p.direct for p in locked] == [True, True, True, False]
    assert problems(["fastapi>=0.141,<1", "numpy>=1.26,<3"], locked) == []


@pytest.mark.parametrize(
    ("wanted", "problem"),
    [
        # A library added to pyproject, the lock not regenerated.
        (["fastapi>=0.141,<1", "numpy>=1.26,<3", "rich>=13"], "rich>=13 is not pinned"),
        # A range raised past the pin, on one of the lock's Python forks.
        (
            ["fastapi>=0.141,<1", "numpy>=2.5"],
            'numpy==2.4.6; python_full_version < "3.12" is outside numpy>=2.5',
        ),
        # A library dropped from pyproject, still pinned as its own.
        (["fastapi>=0.141,<1"], "numpy is pinned as pyproject's own, which no longer names it"),
    ],
)
def test_a_lock_that_pyproject_outgrew_is_stale(wanted: list[str], problem: str) -> None:
    assert problem in problems(wanted, pins(LOCK_TEXT))
