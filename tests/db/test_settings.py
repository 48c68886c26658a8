"""The database URL the settings build: a password given apart reaches the driver intact."""

from hypothesis import given
from hypothesis import strategies as st
from sqlalchemy import make_url

from db import DatabaseSettings, make_engine

BASE = "postgresql+psycopg://calstation@db:5432/calstation"


@given(password=st.text(st.characters(codec="utf-8", exclude_categories=["Cs"]), min_size=1))
def test_any_password_reaches_the_driver_unchanged(password: str) -> None:
    url = DatabaseSettings(database_url=BASE, database_password=password).url()
    parsed = make_url(url)
    assert parsed.password == password
    assert (parsed.username, parsed.host, parsed.port, parsed.database) == (
        "calstation",
        "db",
        5432,
        "calstation",
    )


def test_the_driver_gets_the_password_of_the_compose_example() -> None:
    url = DatabaseSettings(database_url=BASE, database_password="p@ss:w/rd").url()
    engine = make_engine(url)
    _args, kwargs = engine.dialect.create_connect_args(engine.url)
    engine.dispose()
    assert kwargs["password"] == "p@ss:w/rd"
    assert kwargs["host"] == "db"


def test_without_a_password_the_url_is_as_given() -> None:
    assert DatabaseSettings(database_url=BASE).url() == BASE
