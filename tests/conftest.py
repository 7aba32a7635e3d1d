"""Models that several test folders share: built once per test session (a system's symbolic
derivation takes a second or two, and the models are immutable)."""

import pytest

import pendulum_lab as pl


@pytest.fixture(scope="session")
def elastic():
    return pl.elastic_pendulum()


@pytest.fixture(scope="session")
def kapitza():
    return pl.kapitza_pendulum()


@pytest.fixture(scope="session")
def cart():
    return pl.cart_pendulum()


@pytest.fixture(scope="session")
def spherical():
    return pl.spherical_pendulum()
