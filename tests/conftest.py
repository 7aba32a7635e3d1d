"""What several test folders share, made once per test session: models (a system's symbolic
derivation takes a second or two, and the models are immutable), and the notebooks run in
JupyterLab."""

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


@pytest.fixture(scope="session")
def notebooks_run_in_jupyterlab():
    """The notebooks whose run-all in JupyterLab (tests/browser) ended cleanly in this session:
    name -> (the notebook with its outputs, as JupyterLab held it, and the run's seconds).
    The website's build (tests/site, after tests/browser in the same job) shows these outputs
    instead of running the same notebooks under the same package once more."""
    return {}
