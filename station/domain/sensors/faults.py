"""Faults a putter can show, as the virtual putter is told to show them: for testing the
station's reactions (:mod:`station.simulator`). Here, below the simulator, so that
``calstation simulate --help`` lists them without loading the simulator's physics."""

from pydantic import BaseModel, ConfigDict, Field

from station.domain.sensors.sensor import Axis


class Faults(BaseModel):
    """Which faults are on. Assignments are validated, so they may be given as text."""

    model_config = ConfigDict(validate_assignment=True, extra="forbid")

    corrupt_rate: float = Field(
        0.0, ge=0.0, le=1.0, description="fraction of frames sent with one bit flipped"
    )
    drop_rate: float = Field(
        0.0, ge=0.0, le=1.0, description="fraction of samples never sent (sequence gaps)"
    )
    disconnect_after: int | None = Field(
        None, ge=0, description="pull the cable after this many samples of a stream"
    )
    never_settle: bool = Field(False, description="the unit keeps shaking after every move")
    saturate_axis: Axis | None = Field(
        None, description="this accelerometer axis sits at full scale (4095 counts)"
    )
    serial_mismatch: bool = Field(
        False, description="the unit reports another serial number than its label"
    )
    mute: bool = Field(False, description="the firmware ignores every command (no reply)")
