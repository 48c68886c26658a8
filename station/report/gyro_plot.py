"""A plot like [Park2014]_ Fig. 10: scale-factor error against acceleration, per gyro.

For every dwell with rate on gyro i's input axis (|ω_i| ≥ ``MIN_RATE_DPS``), the
scale-factor error in ppm is (ω̂_i − ω_i)/ω_i·10⁶, plotted against the acceleration
along gyro i's sense axis. "Before" compensates bias, S and B only (the ordinary
calibration); "after" the full model, N included. The line is the fitted N_is in
ppm/g. Drawn by matplotlib's Agg canvas (no display), to PNG or SVG by the suffix.
"""

import io
from pathlib import Path
from typing import TYPE_CHECKING, Final

import numpy as np

from station.domain.errors import InputError
from station.domain.gyro.compensation import compensate
from station.domain.gyro.fit import GyroFitReport
from station.domain.gyro.log import GyroLog
from station.domain.gyro.model import PPM, GyroErrorModel
from station.domain.sensors.sensor import AXES

if TYPE_CHECKING:
    from matplotlib.figure import Figure

MIN_RATE_DPS: Final = 10.0
FORMATS: Final = (".png", ".svg")


def sense_axes_of(report: GyroFitReport, model: GyroErrorModel) -> list[int]:
    """Each gyro's sense axis: the fit's, else the axis of its largest N term."""
    return [
        AXES.index(s) if s is not None else int(np.argmax(np.abs(model.n_g[i])))
        for i, s in enumerate(report.sense_axis)
    ]


def plot_g_sensitivity(
    log: GyroLog, model: GyroErrorModel, sense_axes: list[int], path: Path
) -> None:
    """Write the three-panel scale-factor-error plot of ``log`` under ``model`` to ``path``."""
    if path.suffix.lower() not in FORMATS:
        raise InputError(f"{path}: the plot file must end in .png or .svg")
    figure = _figure(log, model, sense_axes)
    try:
        figure.savefig(path, dpi=100)
    except OSError as exc:
        raise InputError(f"{path}: cannot write the plot ({exc.strerror})") from None


def svg_g_sensitivity(log: GyroLog, model: GyroErrorModel, sense_axes: list[int]) -> str:
    """The same plot as an SVG document, to embed in a page."""
    buffer = io.StringIO()
    _figure(log, model, sense_axes).savefig(buffer, format="svg")
    text = buffer.getvalue()
    return text[text.index("<svg") :]


def _figure(log: GyroLog, model: GyroErrorModel, sense_axes: list[int]) -> "Figure":
    # matplotlib is imported when a plot is drawn, not with the report pages: it takes
    # about a second to load, which the server's start and most reports do not need.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    ordinary = GyroErrorModel(model.bias, model.scale, model.bias_g, np.zeros((3, 3)))
    before = compensate(ordinary, log.gyro, log.acc)
    after = compensate(model, log.gyro, log.acc)
    figure = Figure(figsize=(12, 4), layout="constrained")
    FigureCanvasAgg(figure)
    for i, axes in enumerate(figure.subplots(1, 3, sharey=True)):
        s = sense_axes[i]
        rated = np.abs(log.rate[:, i]) >= MIN_RATE_DPS
        acc = log.acc[rated, s]
        rate = log.rate[rated, i]
        axes.plot(acc, (before[rated, i] - rate) / rate * PPM, "o", ms=3, label="before")
        axes.plot(acc, (after[rated, i] - rate) / rate * PPM, "s", ms=3, label="after")
        span = np.array([acc.min(), acc.max()]) if acc.size else np.array([-1.0, 1.0])
        slope = model.n_g[i, s] * PPM
        axes.plot(span, slope * span, "-", color="black", label=f"fit {slope:+.0f} ppm/g")
        axes.set_title(f"gyro {AXES[i]} (sense axis {AXES[s]})")
        axes.set_xlabel(f"acceleration along {AXES[s]} (g)")
        axes.grid(True, alpha=0.3)
        axes.legend(loc="best", fontsize="small")
    figure.axes[0].set_ylabel("scale-factor error (ppm)")
    figure.suptitle("G-sensitivity scale-factor error, before and after compensation")
    return figure
