"""Products by part number: the shipped ones, a sensor that contradicts its limits, labels."""

from pathlib import Path

import numpy as np
import pytest

from station.domain.constants import DEFAULT_PART_NUMBER
from station.domain.errors import InputError
from station.domain.product.limits import load_profiles
from station.domain.product.products import Label, LabelFormat, load_products, parse_products
from station.domain.sensors import sensor
from station.loop.config import load_config
from station.simulator.sensor import ACCEL_NOISE_COUNTS, SensorTruth, accelerometer_counts

SHIPPED = load_products()


def test_the_shipped_products_are_the_putter_and_the_16_bit_generation() -> None:
    assert set(SHIPPED.products) == {"DIXX-A12", "DIXX-D16"}
    limits = load_profiles()
    for product in SHIPPED.products.values():
        product.check(limits, SHIPPED.source)  # each fits its own limits profile
    d16 = SHIPPED.get("DIXX-D16").sensor
    assert (d16.adc_bits, d16.range_g, d16.counts_per_g) == (16, 4.0, 8192.0)
    assert SHIPPED.get("DIXX-D16").limits_profile != SHIPPED.get("DIXX-A12").limits_profile


def test_the_putters_product_is_the_sensor_the_calibration_assumes() -> None:
    a12 = SHIPPED.get(DEFAULT_PART_NUMBER).sensor
    assert a12.adc_max == sensor.ADC_MAX
    assert a12.zero_g_counts == sensor.NOMINAL_OFFSET_COUNTS
    assert a12.counts_per_g == sensor.NOMINAL_SENSITIVITY_COUNTS_PER_G
    assert a12.gyro_dps_per_lsb == sensor.GYRO_DPS_PER_LSB
    assert a12.zero_g_spread_g * a12.counts_per_g == pytest.approx(sensor.OFFSET_SPREAD_COUNTS)
    assert a12.sensitivity_tolerance == sensor.SENSITIVITY_TOLERANCE
    assert a12.noise_g * a12.counts_per_g == pytest.approx(ACCEL_NOISE_COUNTS)
    assert a12.cross_axis == sensor.CROSS_AXIS_TYPICAL  # the budget's model term


def test_a_virtual_putter_follows_its_products_sensor() -> None:
    rng = np.random.default_rng(7)
    for part_number in SHIPPED.products:
        spec = SHIPPED.get(part_number).sensor
        truths = [SensorTruth.draw(rng, spec) for _ in range(50)]
        offsets = np.array([t.offset_counts for t in truths])
        sensitivities = np.array([t.sensitivity_counts_per_g for t in truths])
        spread = spec.zero_g_spread_g * spec.counts_per_g
        assert np.abs(offsets - spec.zero_g_counts).max() <= spread
        assert np.abs(sensitivities / spec.counts_per_g - 1).max() <= spec.sensitivity_tolerance
        assert {t.adc_max for t in truths} == {spec.adc_max}
        # A unit lying face up reads one g on z above its zero g, inside its ADC.
        counts = accelerometer_counts(
            truths[0], np.array([[0.0, 0.0, 1.0]] * 200), np.full(200, 25.0), rng
        )
        assert counts.min() >= 0
        assert counts.max() <= spec.adc_max
        assert counts.mean(axis=0)[2] - truths[0].offset_counts[2] == pytest.approx(
            spec.counts_per_g, rel=0.1
        )


def test_a_product_judged_by_another_sensors_limits_is_refused_in_one_line() -> None:
    text = """
[products.DIXX-X16]
limits_profile = "kxm52-production"
[products.DIXX-X16.sensor]
adc_bits = 16
zero_g_counts = 32768.0
counts_per_g = 8192.0
range_g = 4.0
gyro_dps_per_lsb = 0.02
sample_rate_hz = 500
"""
    product = parse_products(text, "plant.toml").get("DIXX-X16")
    with pytest.raises(InputError) as refused:
        product.check(load_profiles(), "plant.toml")
    assert str(refused.value) == (
        "plant.toml: product DIXX-X16: its sensor contradicts limits profile "
        "kxm52-production: sensitivity_counts_per_g [778.24, 860.16] is not a sensor of "
        "8192 counts/g (outside 4096…16384)"
    )


@pytest.mark.parametrize(
    ("sensor_text", "message"),
    [
        ("adc_bits = 12\nzero_g_counts = 2048.0\ncounts_per_g = 819.2\nrange_g = 4.0", "beyond"),
        ("adc_bits = 24\nzero_g_counts = 0.0\ncounts_per_g = 1.0\nrange_g = 1.0", "adc_bits"),
    ],
)
def test_a_sensor_whose_range_does_not_fit_its_adc_is_refused(
    sensor_text: str, message: str
) -> None:
    text = (
        '[products.P1]\nlimits_profile = "kxm52-production"\n[products.P1.sensor]\n'
        f"{sensor_text}\ngyro_dps_per_lsb = 0.02\nsample_rate_hz = 500\n"
    )
    with pytest.raises(InputError, match=rf"^plant.toml: product P1: .*{message}"):
        parse_products(text, "plant.toml")


def test_an_unknown_part_number_names_the_known_ones() -> None:
    with pytest.raises(
        InputError, match=r"^unknown part number 'DIXX-Z9'; known: DIXX-A12, DIXX-D16$"
    ):
        SHIPPED.get("DIXX-Z9")


def test_a_station_set_to_a_product_runs_its_limits_profile() -> None:
    assert load_config(None, {"part_number": "DIXX-D16"}).limits_profile == "dixx-d16-production"
    assert load_config(None, {}).product.part_number == DEFAULT_PART_NUMBER
    with pytest.raises(InputError, match="unknown part number 'DIXX-Q1'"):
        load_config(None, {"part_number": "DIXX-Q1"})


def test_a_station_whose_limits_contradict_its_product_is_refused(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="product DIXX-D16: its sensor contradicts limits"):
        load_config(None, {"part_number": "DIXX-D16", "limits_profile": "kxm52-production"})


LABEL = LabelFormat(
    pattern=r"(?P<part_number>DIXX-[A-Z0-9]+)/(?P<revision>R\d+)/(?P<serial>PT\d{6})(/(?P<lot>L\w+))?",
    prefix="]C1",
    suffix="\r",
)


def test_a_label_is_read_without_the_scanners_prefix_and_suffix() -> None:
    assert LABEL.read("]C1DIXX-D16/R2/PT000123/L42\r") == Label(
        serial="PT000123", part_number="DIXX-D16", revision="R2", lot="L42"
    )
    assert LABEL.read("DIXX-A12/R1/PT000124") == Label(
        serial="PT000124", part_number="DIXX-A12", revision="R1"
    )
    assert LABEL.read("PT000125") is None


@pytest.mark.parametrize(
    ("pattern", "message"),
    [
        (r"(?P<part_number>\w+)", "no \\(\\?P<serial>"),
        (r"(?P<serial>\w+)(?P<colour>\w+)", "'colour'"),
        (r"(?P<serial>[", "not a regular expression"),
    ],
)
def test_a_label_pattern_needs_a_serial_and_only_known_groups(pattern: str, message: str) -> None:
    with pytest.raises(InputError, match=f"label.*{message}"):
        load_config(None, {"label": {"pattern": pattern}})


def test_a_unit_scanned_under_another_product_than_its_history_is_refused() -> None:
    from station.loop.unit_history import ScanAction, UnitHistory
    from tests.db.records import make_record

    history = UnitHistory("PT-000001", (make_record(part_number="DIXX-D16"),))
    decision = history.at_scan(3, "DIXX-A12")
    assert decision.action is ScanAction.REFUSE
    assert decision.text == (
        "PT-000001 was calibrated as DIXX-D16, scanned as DIXX-A12: set it aside for its "
        "own product's station; nothing was recorded"
    )
    assert history.at_scan(3, "DIXX-D16").action is ScanAction.CONFIRM  # passed already


def test_the_station_reads_labels_and_refuses_another_products(tmp_path: Path) -> None:
    from station.loop.lifecycle import Said, UnitLifecycle

    config = load_config(
        None,
        {
            "data_dir": tmp_path,
            "part_number": "DIXX-D16",
            "label": {"pattern": LABEL.pattern, "prefix": "]C1"},
        },
    )
    lifecycle = UnitLifecycle(
        config=config,
        profile=load_profiles()["dixx-d16-production"],
        slots=[],
        open_store=lambda: None,  # type: ignore[arg-type,return-value]
        say_line=lambda _: None,
    )
    assert lifecycle.read_label("]C1DIXX-D16/R2/PT000123/L42") == Label(
        serial="PT000123", part_number="DIXX-D16", revision="R2", lot="L42"
    )
    assert lifecycle.read_label("]C1DIXX-A12/R1/PT000124") == Said(
        "PT000124 is a DIXX-A12; this station calibrates DIXX-D16: set it aside, nothing "
        "was recorded"
    )
    refused = lifecycle.read_label("PT000125")
    assert isinstance(refused, Said)
    assert refused.text.startswith("'PT000125' is not a label this station reads")
    lifecycle.results.close()
