"""Products by part number, and the labels that name them.

A :class:`Product` is what the line builds under one part number: its accelerometer and
gyros (:class:`station.domain.sensors.sensor_spec.SensorSpec`, whose counts the whole run
follows), the limits profile it is judged by and the run plan it is
run with. The shipped ``station/domain/profiles/products.toml`` holds **DIXX-A12** (the
putter: the KXM52 behind a 12-bit ADC, :mod:`station.domain.sensors.sensor`) and **DIXX-D16** (a
16-bit digital accelerometer, ±4 g, 8192 counts/g); a plant may give its own file.
:meth:`Product.check` refuses, in one line, a product whose sensor contradicts its
limits profile or that names a profile or plan that does not exist; the station checks
its own product when it reads its configuration.

A :class:`LabelFormat` reads a scanned label: the scanner's prefix and suffix taken off,
then a regular expression with named groups ``serial`` (required), ``part_number``,
``revision`` and ``lot`` (:class:`Label`).
"""

from functools import cache
from pathlib import Path
from typing import Self

from pydantic import BaseModel, ConfigDict, ValidationError, model_validator

from station.domain.constants import Identifier, PartNumber
from station.domain.errors import InputError, validation_problem
from station.domain.patterns import full_match, pattern_groups
from station.domain.product.limits import LimitsProfile
from station.domain.product.run_settings import shipped_plan
from station.domain.sensors.sensor_spec import SensorSpec
from station.domain.toml_text import parse_toml, read_text, shipped_text


class Product(BaseModel):
    """One product: its part number, sensor, limits profile and run plan."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    part_number: PartNumber
    description: str = ""
    sensor: SensorSpec
    limits_profile: Identifier
    #: A run plan of ``plans.toml``; None: the plan of the limits profile's name, if one
    #: is shipped, else the six poses of [Song2006]_.
    plan: Identifier | None = None

    def contradiction(self, limits: LimitsProfile) -> str | None:
        """Why ``limits`` cannot judge this product's sensor (None: they can). A plant may
        tighten a profile's bounds as it likes; they contradict the sensor when no unit
        of it could meet them: offset bounds wholly beyond its ADC, or sensitivity bounds
        wholly outside a factor of two of its nominal counts per g (another sensor's)."""
        s = self.sensor
        offset, sensitivity = limits.offset_counts, limits.sensitivity_counts_per_g
        if offset.sides[1] < 0 or offset.sides[0] > s.adc_max:
            return (
                f"offset_counts {offset.describe()} beyond the {s.adc_bits}-bit ADC's 0…{s.adc_max}"
            )
        low, high = s.counts_per_g / 2, s.counts_per_g * 2
        if sensitivity.sides[1] < low or sensitivity.sides[0] > high:
            return (
                f"sensitivity_counts_per_g {sensitivity.describe()} is not a sensor of "
                f"{s.counts_per_g:g} counts/g (outside {low:g}…{high:g})"
            )
        return None

    def check(self, limits: dict[str, LimitsProfile], shown: str) -> None:
        """:class:`InputError` (``shown`` names the file) when the product's limits
        profile or run plan does not exist, or its profile contradicts its sensor."""
        where = f"{shown}: product {self.part_number}"
        profile = limits.get(self.limits_profile)
        if profile is None:
            known = ", ".join(sorted(limits))
            raise InputError(f"{where}: no limits profile {self.limits_profile!r} (known: {known})")
        if self.plan is not None and shipped_plan(self.plan) is None:
            raise InputError(f"{where}: no run plan {self.plan!r}")
        if (why := self.contradiction(profile)) is not None:
            raise InputError(
                f"{where}: its sensor contradicts limits profile {profile.name}: {why}"
            )

    @property
    def run_plan(self) -> str:
        """The name whose shipped run plan the product runs (its plan, else its profile's)."""
        return self.plan or self.limits_profile


class Products(BaseModel):
    """Every product the line builds, by part number."""

    model_config = ConfigDict(frozen=True)

    products: dict[str, Product]
    #: The file they were read from, for errors.
    source: str = "products.toml"

    def get(self, part_number: str) -> Product:
        """The product ``part_number``; :class:`InputError` naming the known ones."""
        product = self.products.get(part_number)
        if product is None:
            known = ", ".join(sorted(self.products))
            raise InputError(f"unknown part number {part_number!r}; known: {known}")
        return product


def parse_products(text: str, shown: str) -> Products:
    """The products of a TOML document ``text`` (``shown`` names it in errors)."""
    tables = parse_toml(text, shown).get("products")
    if not isinstance(tables, dict) or not tables:
        raise InputError(f"{shown}: no [products.PART_NUMBER] table")
    products: dict[str, Product] = {}
    for part_number, table in tables.items():
        if not isinstance(table, dict):
            raise InputError(f"{shown}: product {part_number}: not a table")
        try:
            products[part_number] = Product.model_validate({"part_number": part_number, **table})
        except ValidationError as exc:
            raise InputError(f"{shown}: product {part_number}: {validation_problem(exc)}") from None
    return Products(products=products, source=shown)


def load_products(path: Path | None = None) -> Products:
    """The products of ``path`` (default: the shipped ``products.toml``)."""
    if path is None:
        return parse_products(shipped_text("products.toml"), "products.toml")
    return parse_products(read_text(path, "products"), str(path))


@cache
def shipped_sensor(part_number: str) -> SensorSpec | None:
    """The sensor of the shipped product ``part_number`` (None: not a shipped one)."""
    product = load_products().products.get(part_number)
    return None if product is None else product.sensor


class Label(BaseModel):
    """What a scanned label says: the serial, and the part number, revision and lot
    when the label carries them."""

    model_config = ConfigDict(frozen=True)

    serial: str
    part_number: str | None = None
    revision: str | None = None
    lot: str | None = None


#: The named groups a label pattern may have (``serial`` it must).
LABEL_GROUPS = ("serial", "part_number", "revision", "lot")


class LabelFormat(BaseModel):
    """How the station reads a label: the scanner's ``prefix`` and ``suffix`` (taken off
    when there), then ``pattern``, a regular expression with named groups."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    pattern: str
    prefix: str = ""
    suffix: str = ""

    @model_validator(mode="after")
    def _groups(self) -> Self:
        try:
            groups = pattern_groups(self.pattern)
        except ValueError as exc:
            raise ValueError(f"pattern is {exc}") from None
        if "serial" not in groups:
            raise ValueError("pattern has no (?P<serial>…) group")
        unknown = sorted(groups - set(LABEL_GROUPS))
        if unknown:
            raise ValueError(f"pattern's group {unknown[0]!r} is none of {', '.join(LABEL_GROUPS)}")
        return self

    def read(self, text: str) -> Label | None:
        """The label ``text`` says, or None when it does not match."""
        if self.prefix and text.startswith(self.prefix):
            text = text[len(self.prefix) :]
        if self.suffix and text.endswith(self.suffix):
            text = text[: -len(self.suffix)]
        found = full_match(self.pattern, text)
        if found is None or "serial" not in found:
            return None
        return Label(**found)
