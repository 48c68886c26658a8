"""The unit screen draws a run's view model alone: any moment of a run, without a unit."""

import re

import numpy as np
from rich.console import Console

from station.domain.signals.poses import CALIBRATION_POSES, VERIFICATION_POSE, pose
from station.loop.screens import unit_screen
from station.run.acquisition import StillnessThresholds
from station.run.capture import LiveView
from station.run.messages import Message, MessageLog
from station.run.phases import Phase
from station.run.view import RunView

POSES = tuple(pose(n) for n in (*CALIBRATION_POSES, VERIFICATION_POSE))


def view(phase: Phase, live: LiveView, wrong_unit: str | None = None) -> RunView:
    return RunView(
        serial="PT000001",
        phase=phase,
        poses=POSES,
        index=2,
        taken=frozenset({0, 1}),
        live=live,
        stillness=StillnessThresholds(),
        messages=(Message("warn", "wrong pose: try again"),),
        wrong_unit=wrong_unit,
    )


def drawn(v: RunView) -> str:
    console = Console(record=True, width=120, color_system=None)
    console.print(unit_screen(v))
    return console.export_text()


def test_a_refused_capture_is_drawn_with_its_reason() -> None:
    live = LiveView(accel_std=np.ones(3), progress=1.0, refused="capture refused: moved")
    text = drawn(view(Phase.POSE, live))
    assert "pose 3 of 7" in text
    assert "██ refused" in text
    assert "capture refused: moved" in text
    assert re.search(r"✓1 face up +✓2 face down +▶3 toe up", text)
    assert "wrong pose: try again" in text


def test_another_unit_plugged_in_is_named_while_reconnecting() -> None:
    text = drawn(view(Phase.RECONNECT, LiveView(), wrong_unit="PT000002"))
    assert "PT000002 PLUGGED IN, PT000001 EXPECTED" in text
    assert "pose 3 of 7" not in text


def test_the_log_echoes_only_what_was_said_since() -> None:
    log = MessageLog()
    for i in range(8):
        log.say("info", f"m{i}")
    assert [m.text for m in log] == [f"m{i}" for i in range(2, 8)]
    assert [m.text for m in log.since(6)] == ["m6", "m7"]
    assert [m.text for m in log.since(0)] == [f"m{i}" for i in range(2, 8)]
    assert log.since(8) == []
