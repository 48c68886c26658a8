"""The public surfaces the operator station builds on stay what they are."""

import station.device
import station.run.acquisition
import station.simulator


def test_device_surface() -> None:
    assert set(station.device.__all__) == {
        "DEFAULT_BAUD",
        "DEFAULT_RATE_HZ",
        "MAX_RATE_HZ",
        "PROTOCOL_VERSION",
        "SAMPLE_COLUMNS",
        "DeviceCalibration",
        "DeviceDisconnectedError",
        "DeviceError",
        "DeviceRejectedError",
        "DeviceTimeoutError",
        "Identity",
        "LinkCounters",
        "NoReplyError",
        "ProtocolError",
        "PutterDriver",
        "SerialNumberMismatchError",
    }
    assert station.device.SAMPLE_COLUMNS == ("seq", "ax", "ay", "az", "gx", "gy", "gz", "temp")


def test_simulator_surface() -> None:
    assert set(station.simulator.__all__) == {
        "Faults",
        "Handling",
        "SensorTruth",
        "Thermal",
        "VirtualClock",
        "VirtualPutter",
    }


def test_acquisition_surface() -> None:
    assert set(station.run.acquisition.__all__) == {
        "AcquisitionError",
        "LinkQualityError",
        "NotStillError",
        "PoseAcquisition",
        "PoseResult",
        "SaturatedAxisError",
        "StillnessDetector",
        "StillnessThresholds",
        "WindowVerdict",
        "acquire_pose",
        "judge_window",
    }


def test_every_error_is_one_the_command_line_prints_as_one_line() -> None:
    from station.domain.errors import CalstationError

    for module in (station.device, station.run.acquisition):
        for name in module.__all__:
            obj = getattr(module, name)
            if isinstance(obj, type) and name.endswith("Error"):
                assert issubclass(obj, CalstationError), name
