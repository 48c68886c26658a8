"""The folders are the layers (pyproject.toml's ``layers`` contract, ``lint-imports``).

The contract names packages; this test makes sure nothing sits beside them at the root
of ``station``, so a new module lands in a layer's folder, never loose.
"""

import pkgutil
import tomllib
from pathlib import Path

import station
import station.domain

PYPROJECT = Path(__file__).parents[1] / "pyproject.toml"
#: What ``station``'s root holds besides its layers: the version, and ``python -m station``.
ROOT_MODULES = {"station.__main__"}


#: The domain's packages of data, not code: the shipped profiles and the catalogues.
DOMAIN_DATA = {"profiles", "locale"}
#: The most modules the domain's root holds beside its concepts' packages.
DOMAIN_ROOT_MODULES = 8


def _layers(contract_id: str = "layers") -> list[set[str]]:
    """The names of each layer of the contract ``contract_id``, top first."""
    config = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))
    (layers,) = (
        contract["layers"]
        for contract in config["tool"]["importlinter"]["contracts"]
        if contract["id"] == contract_id
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


def test_every_domain_package_is_a_layer_and_few_modules_sit_at_its_root() -> None:
    found = list(pkgutil.iter_modules(station.domain.__path__))
    packages = {info.name for info in found if info.ispkg} - DOMAIN_DATA
    assert packages == set().union(*_layers("domain-layers"))
    assert len([info for info in found if not info.ispkg]) + 1 <= DOMAIN_ROOT_MODULES
