"""Shared pytest configuration for the whole test suite."""


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        "slow: takes minutes (builds a virtual environment, runs repo2docker); "
        "deselect with -m 'not slow'",
    )
