"""The station's configuration: who and where it is, and how it runs units.

Values come, last one winning, from the defaults here, a TOML file (``--config``),
``CALSTATION_*`` environment variables, and the command line's flags.
"""

import re
from pathlib import Path
from typing import Any, Self
from urllib.parse import urlsplit

from pydantic import Field, ValidationError, field_validator, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict, SettingsError

from station.domain.constants import DEFAULT_PART_NUMBER, MAX_SLOTS, PART_NUMBER_PATTERN
from station.domain.errors import InputError, validation_problem
from station.domain.i18n import Language
from station.domain.patterns import compile_pattern
from station.domain.product.laboratory import Laboratory
from station.domain.product.limits import load_profile
from station.domain.product.products import LabelFormat, Product, Products, load_products
from station.domain.product.run_settings import RunSettings, shipped_plan
from station.domain.quality.golden import GoldenUnit
from station.domain.toml_text import parse_toml
from station.results.storage import DatabaseUrl, DataDir, default_data_dir

#: Serial numbers on the putters' labels: PT and six digits.
SERIAL_PATTERN = r"^PT\d{6}$"


class StationConfig(BaseSettings):
    """One calibration station."""

    model_config = SettingsConfigDict(env_prefix="CALSTATION_", extra="forbid")

    station_id: str = Field("station-1", pattern=r"^[A-Za-z0-9][A-Za-z0-9._:@\-]{0,63}$")
    operator_id: str = Field("operator", pattern=r"^[A-Za-z0-9][A-Za-z0-9._:@\-]{0,63}$")
    #: The production lot of the units being calibrated; recorded on every run.
    lot: str | None = Field(None, pattern=r"^[A-Za-z0-9][A-Za-z0-9._:@\-]{0,63}$")
    port: str | None = None
    #: A multi-slot fixture: one putter port per slot (1 to :data:`MAX_SLOTS`); one
    #: slot is the same as ``port``.
    slots: tuple[str, ...] = Field((), max_length=MAX_SLOTS)
    limits_file: Path | None = None
    limits_profile: str | None = None
    serial_pattern: str = SERIAL_PATTERN
    #: The product this station calibrates (``station.domain.product.products``): its limits
    #: profile and run plan unless ``limits_profile`` names another. None: DIXX-A12.
    part_number: str | None = Field(None, pattern=PART_NUMBER_PATTERN)
    #: The plant's own products (TOML); None: the shipped ``products.toml``.
    products_file: Path | None = None
    #: How a scanned label reads (``[label]``: pattern, prefix, suffix); None: the label
    #: is the bare serial number (``serial_pattern``).
    label: LabelFormat | None = None
    data_dir: DataDir = default_data_dir()
    database_url: DatabaseUrl | None = None
    server_url: str | None = None
    api_key: str | None = None
    run: RunSettings = RunSettings()
    #: The golden unit checked at each shift's start (``[golden]``; none: no check).
    golden: GoldenUnit | None = None
    #: The laboratory its certificates name (``[laboratory]``: name, address,
    #: location, customer, gravity_m_s2, traceability; :mod:`station.domain.product.laboratory`).
    laboratory: Laboratory = Laboratory()
    #: The operator's language (``CALSTATION_LANGUAGE``, ``--language``): the station's
    #: lines from the catalogues of ``station/domain/locale`` (``station.domain.i18n``).
    language: Language = "en"
    #: The TCP port the station serves its Prometheus metrics on while it runs
    #: (:mod:`station.loop.metrics`, ``docs/metrics.md``); None: no metrics served.
    metrics_port: int | None = Field(None, ge=1, le=65535)
    #: The address those metrics are served on (all interfaces: the plant's Prometheus).
    metrics_host: str = "0.0.0.0"

    @model_validator(mode="before")
    @classmethod
    def _plan_of_the_profile(cls, data: Any) -> Any:
        """The shipped run plan of the limits profile, under the configured ``[run]`` keys,
        judging the product's sensor's counts (``[run.stillness]``'s sensor is always the
        product's: its limits not given are derived from it)."""
        if not isinstance(data, dict):
            return data
        product = _products_of(data).get(str(data.get("part_number") or DEFAULT_PART_NUMBER))
        if data.get("part_number") and not data.get("limits_profile"):
            data = {**data, "limits_profile": product.limits_profile}
            plan = shipped_plan(product.run_plan)
        else:
            plan = shipped_plan(data.get("limits_profile"))
        run = data.get("run", {})
        if not isinstance(run, dict):
            return data
        run = {**(plan or {}), **run}
        stillness = run.get("stillness", {})
        if isinstance(stillness, dict):
            run["stillness"] = {**stillness, "sensor": product.sensor}
        return {**data, "run": run}

    @model_validator(mode="after")
    def _product_fits_its_limits(self) -> Self:
        product = self.product
        limits = load_profile(self.limits_file, self.limits_profile)
        why = product.contradiction(limits)
        if why is not None:
            raise ValueError(
                f"product {product.part_number}: its sensor contradicts limits profile "
                f"{limits.name}: {why}"
            )
        return self

    @property
    def product(self) -> Product:
        """The product this station calibrates."""
        return load_products(self.products_file).get(self.part_number or DEFAULT_PART_NUMBER)

    @field_validator("serial_pattern")
    @classmethod
    def _compiles(cls, value: str) -> str:
        compile_pattern(value)  # RE2's, as every scan matches it: refused now, in one line
        return value

    @field_validator("server_url")
    @classmethod
    def _http(cls, value: str | None) -> str | None:
        if value is not None and not (
            urlsplit(value).scheme in ("http", "https") and urlsplit(value).netloc
        ):
            raise ValueError(f"{value!r} is not an http:// or https:// URL")
        return value

    @field_validator("slots")
    @classmethod
    def _one_port_per_slot(cls, value: tuple[str, ...]) -> tuple[str, ...]:
        for i, port in enumerate(value):
            if not port:
                raise ValueError(f"slot {i + 1} names no port")
            if port in value[:i]:
                first = value.index(port) + 1
                raise ValueError(f"slots {first} and {i + 1} both name the port {port}")
        return value

    @model_validator(mode="after")
    def _port_or_slots(self) -> Self:
        if self.slots and self.port:
            raise ValueError("give port (one slot) or slots (several ports), not both")
        if len(self.slots) == 1:  # one slot is the one-port station
            self.port, self.slots = self.slots[0], ()
        return self

    @model_validator(mode="after")
    def _key_for_the_server(self) -> Self:
        if self.server_url and not self.api_key:
            raise ValueError(
                "server_url needs the station's api_key (--api-key, CALSTATION_API_KEY)"
            )
        return self

    @property
    def ports(self) -> tuple[str, ...]:
        """The putter port of every slot (one for the one-port station, none if unset)."""
        return self.slots or ((self.port,) if self.port else ())

    @property
    def journal_path(self) -> Path:
        """The journal of the run in progress (of the one-port station)."""
        return self.data_dir.expanduser() / f"journal-{self.station_id}.json"

    @property
    def queued_label_path(self) -> Path:
        """The label scanned for the next unit during a unit (of the one-port station)."""
        return self.data_dir.expanduser() / f"next-unit-{self.station_id}.txt"

    def slot_queued_label_path(self, slot: int) -> Path:
        """The label scanned ahead for the next cycle's unit in ``slot`` (1-based) of a
        fixture."""
        return self.data_dir.expanduser() / f"next-unit-{self.station_id}-slot{slot}.txt"

    def slot_journal_path(self, slot: int) -> Path:
        """The journal of the run in progress in ``slot`` (1-based) of a fixture."""
        return self.data_dir.expanduser() / f"journal-{self.station_id}-slot{slot}.json"

    @property
    def outbox_dir(self) -> Path:
        """Where finished runs wait to be stored."""
        return self.data_dir.expanduser() / "outbox"


def _products_of(data: dict[str, Any]) -> Products:
    """The products the raw configuration ``data`` names (its file, or the shipped)."""
    products_file = data.get("products_file")
    return load_products(Path(products_file) if products_file else None)


def load_config(
    path: Path | None, overrides: dict[str, Any], defaults: dict[str, Any] | None = None
) -> StationConfig:
    """The configuration from ``path`` (TOML, optional) with ``overrides`` on top;
    ``defaults`` (a command's own, e.g. the demo's station id) stand only for what none of
    the file, the environment and ``overrides`` gives."""
    values: dict[str, Any] = {}
    if path is not None:
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise InputError(
                f"{path}: cannot read the station configuration: {exc.strerror}"
            ) from None
        values = parse_toml(text, str(path))
    if overrides.get("slots"):  # ports on the command line replace the file's
        values.pop("port", None)
        values.pop("slots", None)
    values.update({k: v for k, v in overrides.items() if v is not None})
    try:
        config = StationConfig(**values)
        unset = {k: v for k, v in (defaults or {}).items() if k not in config.model_fields_set}
        return StationConfig(**unset, **values) if unset else config
    except ValidationError as exc:
        where = f"{path}: " if path is not None else ""
        raise InputError(f"{where}station configuration: {validation_problem(exc)}") from None
    except SettingsError as exc:  # an environment variable that is not valid JSON
        raise InputError(f"station configuration: {_env_problem(exc)}") from None


def _env_problem(exc: SettingsError) -> str:
    """``CALSTATION_RUN: not valid JSON (…)`` from pydantic-settings' error."""
    field = re.search(r'field "([^"]+)"', str(exc))
    name = f"CALSTATION_{field.group(1).upper()}" if field else "a CALSTATION_ variable"
    cause = exc.__cause__
    return f"{name}: not valid JSON ({cause})" if cause is not None else f"{name}: {exc}"
