"""Alerts a plant sets in its configuration, and the alerts that fired.

A rule watches the line; while its condition holds it has one open alert, which fired
once (its ``event_key``) and is posted to the plant's webhook once; when the condition
no longer holds the alert clears, and the next time it holds is a new event. Rules:

- ``yield``: the first-pass yield of the last ``units`` units (their first run on the
  line, at ``station`` or anywhere) below ``goal``, once ``units`` units are there.
- ``silent``: no run from ``station`` for ``minutes`` (60 by default) since its last
  run (a station that never stored a run is not watched).
- ``western_electric``: the latest run's ``parameter`` (a coefficient) completes a
  Western Electric rule (:mod:`station.domain.quality.control`) on the individuals
  chart of the last ``runs`` runs (at ``station`` or anywhere), its centre and σ = MR̄/d₂
  from those runs.
- ``cpk``: the Cpk of ``parameter`` (a coefficient) over the last ``runs`` runs (at
  ``station`` or anywhere), against the limits profile of the latest of them, below
  ``target`` (1.33 by default, :data:`station.domain.quality.capability.CAPABLE_CPK`).
- ``outbox``: a station's latest outbox report (:mod:`station.domain.record.outbox_report`,
  sent with each run) says ``queued`` runs or more wait behind the run it sent (20 by
  default), or the oldest of them has waited ``hours`` or more (1 by default), or a file
  is set aside (refused or unreadable); one alert per station (``station`` or every
  station that reported), cleared by a later report under all three.

The rules file is TOML (``CALSTATION_ALERTS_FILE``)::

    webhook = "https://chat.example/hooks/line2"

    [[yield]]
    station = "line2-st1"   # optional: the whole line without it
    units = 20
    goal = 0.9

    [[silent]]
    station = "line2-st1"
    minutes = 60

    [[western_electric]]
    parameter = "offset_x"
    runs = 50

    [[cpk]]
    parameter = "sensitivity_z"
    runs = 100
    target = 1.33

    [[outbox]]
    station = "line2-st1"   # optional: every station without it
    queued = 20
    hours = 1
"""

from datetime import datetime
from typing import Annotated, Literal

from pydantic import AnyHttpUrl, BaseModel, ConfigDict, Field, JsonValue, ValidationError

from station.domain.constants import Identifier
from station.domain.errors import InputError, validation_problem
from station.domain.quality.capability import CAPABLE_CPK
from station.domain.quality.parameters import COEFFICIENTS
from station.domain.toml_text import parse_toml

#: The kinds of rule.
RuleKind = Literal["yield", "silent", "western_electric", "cpk", "outbox"]


class _Rules(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class YieldRule(_Rules):
    """First-pass yield of the last ``units`` units below ``goal``."""

    station: Identifier | None = None
    units: Annotated[int, Field(ge=1, le=10_000)]
    goal: Annotated[float, Field(gt=0, le=1)]

    @property
    def scope(self) -> str:
        """What the rule watches: its station, or the line."""
        return self.station or "line"


class SilentRule(_Rules):
    """No run from ``station`` for ``minutes`` since its last one."""

    station: Identifier
    minutes: Annotated[float, Field(gt=0, le=7 * 24 * 60)] = 60.0

    @property
    def scope(self) -> str:
        """What the rule watches: its station."""
        return self.station


class ParameterWindow(_Rules):
    """A rule over a coefficient's values of the last ``runs`` runs (at ``station``)."""

    parameter: Literal[COEFFICIENTS]  # type: ignore[valid-type]
    station: Identifier | None = None
    runs: Annotated[int, Field(ge=10, le=1000)] = 50

    @property
    def scope(self) -> str:
        """What the rule watches: its station, or the line."""
        return self.station or "line"


class WesternElectricRule(ParameterWindow):
    """The latest run's ``parameter`` completes a Western Electric rule on the chart of
    the last ``runs`` runs."""


class CpkRule(ParameterWindow):
    """The Cpk of ``parameter`` over the last ``runs`` runs below ``target``."""

    target: Annotated[float, Field(gt=0, le=10)] = CAPABLE_CPK


class OutboxRule(_Rules):
    """A station's latest outbox report: ``queued`` runs or more waiting, the oldest
    waiting ``hours`` or more, or a file set aside."""

    station: Identifier | None = None
    queued: Annotated[int, Field(ge=1, le=1_000_000)] = 20
    hours: Annotated[float, Field(gt=0, le=30 * 24)] = 1.0


class AlertRules(_Rules):
    """The plant's alert rules and where their alerts go."""

    webhook: AnyHttpUrl
    yield_rules: list[YieldRule] = Field(default_factory=list, alias="yield")
    silent_rules: list[SilentRule] = Field(default_factory=list, alias="silent")
    western_electric_rules: list[WesternElectricRule] = Field(
        default_factory=list, alias="western_electric"
    )
    cpk_rules: list[CpkRule] = Field(default_factory=list, alias="cpk")
    outbox_rules: list[OutboxRule] = Field(default_factory=list, alias="outbox")


def parse_alert_rules(text: str, shown: str) -> AlertRules:
    """The rules of a TOML file (``shown``: its name in a problem), or an
    :class:`InputError` naming what is wrong."""
    try:
        return AlertRules.model_validate(parse_toml(text, shown))
    except ValidationError as exc:
        raise InputError(f"{shown}: {validation_problem(exc)}") from None


class Alert(BaseModel):
    """An alert that fired: its rule and scope, when, the evidence and the runs behind it."""

    model_config = ConfigDict(frozen=True)

    event_key: str = Field(description="the event, unique: posted to the webhook once")
    rule: RuleKind
    scope: str = Field(description="the station the rule watches, or `line`")
    message: str
    fired_at: datetime
    cleared_at: datetime | None = Field(description="when the condition stopped holding")
    delivered_at: datetime | None = Field(description="when the webhook took it")
    attempts: int = Field(description="posts to the webhook so far")
    evidence: dict[str, JsonValue] = Field(
        description="what fired it: the figures and the first runs of the units behind them"
    )
