"""The virtual putter: sensor and motion physics behind the real protocol.

Public surface::

    with VirtualPutter(seed=7, serial="PT000007", speed=20) as unit:
        url = unit.serve_pty()            # or unit.serve_socket()
        unit.move_to("toe_up", wait=True)
        unit.truth.offset_counts
"""

from station.domain.sensors.faults import Faults
from station.simulator.clock import VirtualClock
from station.simulator.motion import Handling
from station.simulator.putter import VirtualPutter
from station.simulator.sensor import SensorTruth, Thermal

__all__ = ["Faults", "Handling", "SensorTruth", "Thermal", "VirtualClock", "VirtualPutter"]
