"""The folders are the layers (pyproject.toml's ``layers`` contract, ``lint-imports``).

The contract names packages; this test makes sure nothing sits beside them at the root
of ``station``, so a new module lands in a layer's folder, never loose.
"""

import pkgutil
import tomllib
from pathlib import Path

import station

PYPROJECT = Path(__file__).parents[1] / "pyproject.toml"
#: What ``station``'s root holds besides its layers: the version, and ``python -m station``.
ROOT_MODULES = {"station.__main__"}


def _layers() -> list[set[str]]:
    """The names of each layer of the ``layers`` contract, top first."""
    config = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))
    (layers,) = (
        contract["layers"]
        for contract in config["tool"]["importlinter"]["contracts"]
        if contract["id"] == "layers"
    )
    return [{name.strip() for name in layer.replace("|", ":").split(":")} for layer in layers]


def test_every_station_package_is_a_layer_and_no_module_sits_loose() -> None:
    named = set().union(*_layers())
    found = {f"station.{info.name}" for info in pkgutil.iter_modules(station.__path__)}
    assert "station.domain" in found
    assert found - ROOT_MODULES == {name for name in named if name.startswith("station.")}


def test_the_contract_names_few_packages_in_many_layers() -> None:
    layers = _layers()
    assert len(layers) >= 6
    assert sum(len(layer) for layer in layers) <= 12
