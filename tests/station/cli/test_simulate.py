"""``calstation simulate`` as a real process, driven through its control channel."""

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from station.device import DeviceDisconnectedError, PutterDriver, SerialNumberMismatchError
from station.domain.signals.poses import pose
from station.run.acquisition import acquire_pose
from tests.conftest import REPO_ROOT, CliRunner


class Simulator:
    """A running ``calstation simulate`` with its control channel."""

    def __init__(self, *args: str) -> None:
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO_ROOT), env.get("PYTHONPATH")]))
        self.process = subprocess.Popen(
            [sys.executable, "-m", "station", "simulate", *args],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        first = self.line()
        assert first.startswith("url "), first
        self.url = first.removeprefix("url ")

    def line(self) -> str:
        assert self.process.stdout is not None
        return self.process.stdout.readline().strip()

    def send(self, command: str) -> str:
        assert self.process.stdin is not None
        self.process.stdin.write(command + "\n")
        self.process.stdin.flush()
        return self.line()

    def close(self) -> int:
        if self.process.poll() is None:
            assert self.send("quit") == "ok"
        self.process.communicate(timeout=10)
        return self.process.returncode


@pytest.fixture
def simulator(tmp_path: Path) -> Iterator[Simulator]:
    sim = Simulator(
        "--pty",
        "--link",
        str(tmp_path / "putter"),
        "--speed",
        "25",
        "--seed",
        "8",
        "--serial",
        "PT000808",
    )
    yield sim
    sim.close()


def test_the_simulator_is_moved_and_faulted_from_outside(simulator: Simulator) -> None:
    truth = json.loads(simulator.send("truth").removeprefix("ok "))
    with PutterDriver.open(simulator.url) as driver:
        assert driver.identify(expected_serial="PT000808").sensor_part == "KXM52-1050"
        driver.start_stream()
        reply = simulator.send("pose toe_up 1.0")
        assert reply.startswith("ok from_seq ")
        assert simulator.send("settle") == "ok"
        from_seq = int(reply.removeprefix("ok from_seq "))
        result = acquire_pose(driver, pose="toe_up", timeout_s=10.0, from_seq=from_seq)
        expected = np.array(truth["offset_counts"]) + np.array(
            truth["sensitivity_counts_per_g"]
        ) * (np.array(truth["cross_axis"]) @ pose("toe_up").gravity_body)
        np.testing.assert_allclose(result.summary.accel_mean, expected, atol=1.0)
        assert simulator.send("fault serial_mismatch true") == "ok"
        with pytest.raises(SerialNumberMismatchError):
            driver.identify(expected_serial="PT000808")
        assert simulator.send("unplug") == "ok"
        with pytest.raises(DeviceDisconnectedError):
            driver.wait_samples(10**6, timeout=5.0)
    # The --link name survives the replug.
    assert simulator.send("replug") == f"ok {simulator.url}"
    with PutterDriver.open(simulator.url) as driver:
        assert driver.identify().serial != "PT000808"


def test_control_errors_are_one_line_and_the_simulator_carries_on(simulator: Simulator) -> None:
    assert simulator.send("fault drop_rate 7").startswith("error fault drop_rate:")
    assert simulator.send("pose upside").startswith("error unknown pose 'upside'")
    assert simulator.send("dance").startswith("error unknown command 'dance'")
    assert simulator.send("fault drop_rate 0.5") == "ok"
    assert json.loads(simulator.send("faults").removeprefix("ok "))["drop_rate"] == 0.5
    assert simulator.close() == 0


def test_it_serves_a_socket_too() -> None:
    sim = Simulator("--listen", "127.0.0.1:0", "--serial", "PT000777")
    try:
        assert sim.url.startswith("socket://127.0.0.1:")
        with PutterDriver.open(sim.url) as driver:
            assert driver.identify().serial == "PT000777"
    finally:
        assert sim.close() == 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((), "give exactly one of --pty or --listen HOST:PORT"),
        (("--listen", "nowhere"), "--listen: expected HOST:PORT, got 'nowhere'"),
        (("--pty", "--fault", "drop_rate"), "--fault: expected NAME=VALUE, got 'drop_rate'"),
        (("--pty", "--fault", "wobble=1"), "--fault wobble: Extra inputs are not permitted"),
        (("--pty", "--rate", "5000"), "--rate must be 1…1000 samples/s, got 5000"),
        (("--pty", "--serial", "X" * 17), "--serial: 1 to 16 ASCII characters"),
    ],
)
def test_bad_options_give_one_line_and_exit_2(
    run_cli: CliRunner, args: tuple[str, ...], message: str
) -> None:
    result = run_cli("simulate", *args, input="")
    assert result.returncode == 2
    assert result.stderr.strip().startswith(f"calstation: error: {message}")
    assert len(result.stderr.strip().splitlines()) == 1
