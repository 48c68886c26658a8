"""The import contracts (pyproject.toml, checked by ``lint-imports`` in ``make lint``).

``lint-imports`` checks only the modules a layer names; this test makes sure every
module and package of ``station`` is named, so a new one gets a layer before it lands.
"""

import pkgutil
import tomllib
from pathlib import Path

import station

PYPROJECT = Path(__file__).parents[1] / "pyproject.toml"


def _layered_modules() -> set[str]:
    """Every module named in a layer of the ``layers`` contract."""
    config = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))
    (layers,) = (
        contract["layers"]
        for contract in config["tool"]["importlinter"]["contracts"]
        if contract["id"] == "layers"
    )
    return {name.strip() for layer in layers for name in layer.replace("|", ":").split(":")}


def test_every_station_module_stands_in_a_layer() -> None:
    modules = {f"station.{info.name}" for info in pkgutil.iter_modules(station.__path__)}
    assert "station.session" in modules
    assert modules - _layered_modules() == set()
