"""The identifiability check names what a log cannot estimate, and why."""

import numpy as np
import pytest

from station.domain.errors import InputError
from station.domain.gyro.identifiability import NotIdentifiableError, check_identifiability
from station.domain.gyro.log import GyroLog
from station.domain.gyro.model import GyroErrorModel
from station.domain.gyro.simulate import CentrifugePlan, Mount, simulate_log

SINGLE_MOUNT = CentrifugePlan(mounts=(Mount(0, 1, 1, 1),), rate_table=False)


def test_the_full_plan_determines_every_term(paper_log: GyroLog) -> None:
    report = check_identifiability(paper_log)
    assert report.unestimable() == []
    for axis in report.axes:
        assert axis.rank == 10
        assert axis.condition_number is not None
        assert axis.condition_number < 100
        assert axis.form_question
    report.require_form_question()


def test_single_mount_centrifuge_is_refused_for_the_form_question(
    paper_model: GyroErrorModel,
) -> None:
    log, _ = simulate_log(paper_model, SINGLE_MOUNT, seed=1)
    report = check_identifiability(log)
    with pytest.raises(NotIdentifiableError, match="bias-form from scale-factor-form") as caught:
        report.require_form_question()
    assert "gyro x" in str(caught.value)
    for term, nonlinearity in (("B_xy", "ω²"), ("N_xy", "ω³")):
        status = report.status(term)
        assert not status.estimable
        assert status.reason is not None
        assert nonlinearity in status.reason
        assert "flip the mount" in status.reason
    assert report.status("S_xx").estimable
    assert report.status("bias_x").estimable


def test_single_mount_with_gravity_statics_still_refuses_the_scale_factor_term(
    paper_model: GyroErrorModel,
) -> None:
    plan = CentrifugePlan(mounts=(Mount(0, 1, 1, 1),), table_rates_dps=())
    log, _ = simulate_log(paper_model, plan, seed=2)
    report = check_identifiability(log)
    assert report.status("B_xy").estimable  # the tilt statics give the bias form
    assert not report.status("N_xy").estimable
    assert not report.axes[0].form_question


def test_gravity_one_way_along_the_input_axis_leaves_n_ii_unestimable(
    paper_model: GyroErrorModel,
) -> None:
    rate = np.zeros((20, 3))
    rate[:, 2] = np.tile([-300.0, -100.0, 0.0, 100.0, 300.0], 4)
    acc = np.zeros((20, 3))
    acc[:, 2] = 1.0
    log = GyroLog(np.arange(20.0), rate, acc, paper_model.predict(rate, acc))
    report = check_identifiability(log)
    status = report.status("N_zz")
    assert not status.estimable
    assert status.reason is not None
    assert "both signs" in status.reason
    assert "S_zz includes N_zz × +1.00 g" in report.axes[2].caveats
    assert "bias_z includes B_zz × +1.00 g" in report.axes[2].caveats
    assert "no rate about x" in (report.status("S_zx").reason or "")


def test_exactly_collinear_columns_name_each_other(paper_model: GyroErrorModel) -> None:
    rate = np.zeros((30, 3))
    rate[:, 0] = np.linspace(-300.0, 300.0, 30)
    acc = np.zeros((30, 3))
    acc[:, 1] = np.linspace(-2.0, 2.0, 30)
    acc[:, 2] = 2.0 * acc[:, 1]  # z always twice y: B_.y and B_.z cannot be told apart
    acc[:, 0] = np.where(np.arange(30) % 2, 1.0, -1.0)
    log = GyroLog(np.arange(30.0), rate, acc, paper_model.predict(rate, acc))
    report = check_identifiability(log)
    for term, partner in (("B_yy", "B_yz"), ("B_yz", "B_yy")):
        status = report.status(term)
        assert not status.estimable
        assert status.reason is not None
        assert partner in status.reason
    assert report.status("B_yx").estimable
    assert report.axes[1].condition_number is None


def test_an_empty_log_is_refused() -> None:
    empty = np.zeros((0, 3))
    with pytest.raises(InputError, match="no dwells"):
        check_identifiability(GyroLog(np.zeros(0), empty, empty, empty))
