"""calstation: the smart putter's production-line calibration station.

The station package holds everything that runs at the line: the calibration math
(:mod:`station.domain.calibration`), the sensor constants (:mod:`station.domain.sensors.sensor`) and
the
command-line interface (:mod:`station.cli`).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("calstation")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+source"

__all__ = ["__version__"]
