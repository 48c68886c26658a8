"""Run plans shipped beside the limits profiles: the ``[run]`` settings a profile needs.

``station/domain/profiles/plans.toml`` holds one ``[plans.NAME]`` table per profile that is
not run the default way (six poses, [Song2006]_). :func:`shipped_plan` gives the
table of a profile name, which :class:`station.loop.config.StationConfig` takes as its
``[run]`` defaults, so that ``--profile whole-unit`` chooses the limits and the poses,
model and gyro calibration together.
"""

import tomllib
from functools import cache
from importlib import resources
from typing import Any


@cache
def _plans() -> dict[str, dict[str, Any]]:
    text = (
        resources.files("station.domain.profiles")
        .joinpath("plans.toml")
        .read_text(encoding="utf-8")
    )
    plans: dict[str, dict[str, Any]] = tomllib.loads(text)["plans"]
    return plans


def shipped_plan(profile: object) -> dict[str, Any] | None:
    """The ``[run]`` settings shipped for limits profile ``profile``, or None."""
    if not isinstance(profile, str):
        return None
    plan = _plans().get(profile)
    return dict(plan) if plan is not None else None
