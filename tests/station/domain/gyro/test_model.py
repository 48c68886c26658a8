"""The error model: forward prediction and its regressors agree."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from station.domain.gyro.model import GyroErrorModel, regressors, term_names

finite = st.floats(-1e3, 1e3, allow_nan=False)


@given(
    coefficients=arrays(np.float64, (3, 10), elements=st.floats(-2, 2, allow_nan=False)),
    rate=arrays(np.float64, (5, 3), elements=finite),
    acc=arrays(np.float64, (5, 3), elements=st.floats(-40, 40, allow_nan=False)),
)
def test_regressors_reproduce_the_prediction(
    coefficients: np.ndarray, rate: np.ndarray, acc: np.ndarray
) -> None:
    rows = coefficients  # each gyro's row: bias, scale row, bias-g row, g-sensitivity row
    model = GyroErrorModel(rows[:, 0], rows[:, 1:4], rows[:, 4:7], rows[:, 7:10])
    predicted = model.predict(rate, acc)
    for axis in range(3):
        np.testing.assert_allclose(
            regressors(axis, rate, acc) @ model.row(axis), predicted[:, axis], atol=1e-6
        )


def test_term_names_follow_the_regressor_columns() -> None:
    assert term_names(1) == [
        "bias_y",
        *(f"S_y{a}" for a in "xyz"),
        *(f"B_y{a}" for a in "xyz"),
        *(f"N_y{a}" for a in "xyz"),
    ]


def test_ideal_gyro_reads_the_rate() -> None:
    rate = np.array([[100.0, -50.0, 3.0]])
    np.testing.assert_array_equal(GyroErrorModel.ideal().predict(rate, np.ones((1, 3))), rate)


@pytest.mark.parametrize(
    ("field", "value"), [("bias", np.zeros(2)), ("scale", np.full((3, 3), np.nan))]
)
def test_model_refuses_bad_coefficients(field: str, value: np.ndarray) -> None:
    parts = {"bias": np.zeros(3), "scale": np.eye(3), "bias_g": np.zeros((3, 3))}
    parts[field] = value
    with pytest.raises(ValueError, match=field):
        GyroErrorModel(parts["bias"], parts["scale"], parts["bias_g"], np.zeros((3, 3)))
