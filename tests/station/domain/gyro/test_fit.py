"""The fit recovers a known truth, within tolerances that follow from the noise."""

import numpy as np
import pytest

from station.domain.errors import InputError
from station.domain.gyro.fit import GyroFitReport, fit_log
from station.domain.gyro.identifiability import NotIdentifiableError
from station.domain.gyro.log import GyroLog
from station.domain.gyro.model import PPM, GyroErrorModel
from station.domain.gyro.simulate import CentrifugePlan, Mount, Noise, paper_truth, simulate_log

#: Every estimate must lie within this many of its own standard errors of the truth.
#: The standard errors come from the residual noise (0.01 deg/s per dwell), so this is
#: the noise-derived tolerance; the test below checks they are honest.
K_SIGMA = 5.0
BIAS_FORM = (0.01, 0.02, -0.01)  # deg/s/g on the sense axis


def _estimates(report: GyroFitReport) -> tuple[np.ndarray, np.ndarray]:
    """Estimates and standard errors as 3-by-10 arrays in model-row order (N in 1/g)."""
    se = report.standard_errors
    rows, errors = [], []
    for i in range(3):
        rows.append(
            [
                report.bias_dps[i],
                *report.scale_matrix[i],
                *report.bias_g_sensitivity_dps_per_g[i],
                *(v / PPM for v in report.g_sensitivity_ppm_per_g[i]),
            ]
        )
        errors.append(
            [
                se.bias_dps[i],
                *se.scale_matrix[i],
                *se.bias_g_sensitivity_dps_per_g[i],
                *(v / PPM for v in se.g_sensitivity_ppm_per_g[i]),
            ]
        )
    return np.array(rows, dtype=float), np.array(errors, dtype=float)


def _truth_rows(model: GyroErrorModel) -> np.ndarray:
    return np.array([model.row(i) for i in range(3)])


@pytest.mark.parametrize(
    ("truth", "verdict"),
    [
        (paper_truth(), "scale-factor"),
        (paper_truth(ppm_per_g=(0.0, 0.0, 0.0), bias_form_dps_per_g=BIAS_FORM), "bias"),
        (paper_truth(bias_form_dps_per_g=BIAS_FORM), "both"),
        (paper_truth(ppm_per_g=(0.0, 0.0, 0.0)), "none"),
    ],
    ids=["scale-factor-only", "bias-form-only", "both", "no-g-term"],
)
def test_fit_recovers_the_truth_and_names_its_form(truth: GyroErrorModel, verdict: str) -> None:
    log, _ = simulate_log(truth, noise=Noise(gyro_dps=0.01, acc_g=0.001), seed=11)
    report = fit_log(log)
    estimate, stderr = _estimates(report)
    assert np.all(np.abs(estimate - _truth_rows(truth)) <= K_SIGMA * stderr)
    # With 0.01 deg/s per dwell the sense-axis terms are known to well under 1 ppm/g.
    assert max(report.standard_errors.g_sensitivity_ppm_per_g[0]) < 6.0
    assert report.standard_errors.g_sensitivity_ppm_per_g[0][1] < 0.5
    assert all(r == pytest.approx(0.01, rel=0.2) for r in report.residual_rms_dps)
    assert [c.verdict for c in report.comparison] == [verdict] * 3
    assert report.unestimable == []
    expected_sense = ["y", "z", "y"] if verdict in ("scale-factor", "both") else [None] * 3
    assert report.sense_axis == expected_sense


def test_standard_errors_are_honest() -> None:
    truth = paper_truth(bias_form_dps_per_g=BIAS_FORM)
    z = []
    for seed in range(12):
        log, _ = simulate_log(truth, seed=seed)
        estimate, stderr = _estimates(fit_log(log))
        z.append((estimate - _truth_rows(truth)) / stderr)
    spread = float(np.std(np.array(z)))
    assert 0.8 < spread < 1.25


def test_averaged_segments_fit_like_dwells(paper_model: GyroErrorModel) -> None:
    log, segments = simulate_log(
        paper_model, noise=Noise(gyro_dps=0.1, acc_g=0.01), samples_per_dwell=100, seed=5
    )
    assert segments is not None
    dwell_log = _average(log, segments)
    report = fit_log(dwell_log)
    estimate, stderr = _estimates(report)
    assert np.all(np.abs(estimate - _truth_rows(paper_model)) <= K_SIGMA * stderr)


def _average(log: GyroLog, segments: list[str]) -> GyroLog:
    labels = np.array([int(s[1:]) for s in segments])
    count = labels.max() + 1

    def mean(values: np.ndarray) -> np.ndarray:
        sums = np.zeros((count, *values.shape[1:]))
        np.add.at(sums, labels, values)
        return sums / np.bincount(labels)[(slice(None), *([None] * (values.ndim - 1)))]

    return GyroLog(mean(log.t), mean(log.rate), mean(log.acc), mean(log.gyro))


def test_unestimable_terms_are_none_with_reason(paper_model: GyroErrorModel) -> None:
    log, _ = simulate_log(
        paper_model, CentrifugePlan(mounts=(Mount(0, 1, 1, 1),), rate_table=False)
    )
    report = fit_log(log)
    assert report.g_sensitivity_ppm_per_g[0][1] is None
    assert report.standard_errors.g_sensitivity_ppm_per_g[0][1] is None
    assert report.bias_g_sensitivity_dps_per_g[0][1] is None
    assert report.scale_matrix[0][0] is not None
    named = {t.term: t.reason for t in report.unestimable}
    assert {"B_xy", "N_xy", "S_yy", "N_zz"} <= set(named)
    assert all(named.values())
    assert [c.verdict for c in report.comparison] == [None, None, None]
    assert report.sense_axis == [None, None, None]
    assert report.sense_axis_reason[0] == "no N term is estimable from this log"
    assert report.sense_axis_reason[1] == "no N term is estimable from this log"
    with pytest.raises(NotIdentifiableError, match="N_xy"):
        report.error_model()


def test_report_round_trips_through_json(paper_log: GyroLog) -> None:
    report = fit_log(paper_log)
    back = GyroFitReport.from_dict(report.to_dict())
    assert back == report
    np.testing.assert_array_equal(back.error_model().n_g, report.error_model().n_g)


def test_too_few_dwells_are_refused(paper_log: GyroLog) -> None:
    short = GyroLog(paper_log.t[:10], paper_log.rate[:10], paper_log.acc[:10], paper_log.gyro[:10])
    with pytest.raises(InputError, match=r"10 dwells in the log; .* at least 11"):
        fit_log(short)
