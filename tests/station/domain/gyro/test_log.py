"""Reading and validating logs: round trip, segments, and one-line errors."""

import io
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from station.domain.errors import InputError
from station.domain.gyro.log import NUMERIC_COLUMNS, GyroLog, read_log, write_log

HEADER = ",".join(NUMERIC_COLUMNS)
ROW = ",".join(["0"] * len(NUMERIC_COLUMNS))


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


@settings(max_examples=25, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    table=arrays(
        np.float64, st.tuples(st.integers(1, 8), st.just(10)), elements=st.floats(-1e6, 1e6)
    )
)
def test_write_then_read_gives_the_same_log(tmp_path: Path, table: np.ndarray) -> None:
    log = GyroLog(t=table[:, 0], rate=table[:, 1:4], acc=table[:, 4:7], gyro=table[:, 7:10])
    buffer = io.StringIO()
    write_log(buffer, log)
    back = read_log(_write(tmp_path / "log.csv", buffer.getvalue()))
    for name in ("t", "rate", "acc", "gyro"):
        np.testing.assert_array_equal(getattr(back, name), getattr(log, name))


def test_segments_are_averaged_in_order_of_first_appearance(tmp_path: Path) -> None:
    rows = ["0,1,0,0,0,0,1,1,0,0,b", "1,3,0,0,0,0,1,3,0,0,b", "2,5,0,0,0,0,1,5,0,0,a"]
    log = read_log(_write(tmp_path / "s.csv", HEADER + ",segment\n" + "\n".join(rows) + "\n"))
    np.testing.assert_array_equal(log.t, [0.5, 2.0])
    np.testing.assert_array_equal(log.rate[:, 0], [2.0, 5.0])
    np.testing.assert_array_equal(log.gyro[:, 0], [2.0, 5.0])


def test_columns_may_come_in_any_order_with_extras(tmp_path: Path) -> None:
    names = [*reversed(NUMERIC_COLUMNS), "temperature"]
    values = [str(float(k)) for k in range(len(names))]
    log = read_log(_write(tmp_path / "r.csv", ",".join(names) + "\n" + ",".join(values) + "\n"))
    assert log.t[0] == float(names.index("t"))
    assert log.gyro[0, 2] == float(names.index("gyro_z"))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", r"empty file"),
        ("t,rate_ref_x\n0,0\n", r"missing column rate_ref_y, .*gyro_z"),
        (
            HEADER + "\n" + ROW + "\n" + ROW.replace("0", "abc", 1) + "\n",
            r":3: column t: 'abc' is not a number",
        ),
        (
            HEADER + "\n" + ROW + "\n" + ROW[:-1] + "nan\n",
            r":3: column gyro_z: 'nan' is not finite",
        ),
        (HEADER + "\n0,0\n", r":2: 2 cells, the header has 10"),
        (HEADER + ",segment\n" + ROW + ",\n", r":2: column segment: empty label"),
    ],
)
def test_bad_logs_give_one_line_naming_file_and_line(
    tmp_path: Path, text: str, message: str
) -> None:
    path = _write(tmp_path / "bad.csv", text)
    with pytest.raises(InputError, match=message) as caught:
        read_log(path)
    assert str(caught.value).startswith(str(path))
    assert "\n" not in str(caught.value)


def test_missing_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"nope\.csv: no such file"):
        read_log(tmp_path / "nope.csv")


def test_binary_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "bin.csv"
    path.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(InputError, match="not a UTF-8 text file"):
        read_log(path)
