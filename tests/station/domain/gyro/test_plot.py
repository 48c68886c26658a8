"""The Fig. 10-style plot is written as PNG or SVG."""

from pathlib import Path

import pytest

from station.domain.errors import InputError
from station.domain.gyro.fit import fit_log
from station.domain.gyro.log import GyroLog
from station.report.gyro_plot import plot_g_sensitivity


@pytest.mark.parametrize(("name", "magic"), [("fig.png", b"\x89PNG"), ("fig.svg", b"<?xml")])
def test_plot_is_written(tmp_path: Path, paper_log: GyroLog, name: str, magic: bytes) -> None:
    model = fit_log(paper_log).error_model()
    path = tmp_path / name
    plot_g_sensitivity(paper_log, model, [1, 2, 1], path)
    assert path.read_bytes().startswith(magic)
    if name.endswith(".svg"):
        text = path.read_text(encoding="utf-8")
        assert "+581 ppm/g" in text
        assert "-613 ppm/g" in text


def test_other_formats_are_refused(tmp_path: Path, paper_log: GyroLog) -> None:
    model = fit_log(paper_log).error_model()
    with pytest.raises(InputError, match=r"fig\.pdf: the plot file must end in \.png or \.svg"):
        plot_g_sensitivity(paper_log, model, [1, 2, 1], tmp_path / "fig.pdf")
