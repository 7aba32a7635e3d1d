"""What several test folders share: models made once per test session (a system's symbolic
derivation takes a second or two, and the models are immutable), the notebooks run in
JupyterLab, and the guard of the refusals that must come before any work."""

import contextlib
import tracemalloc

import pytest

import pendulum_lab as pl
from pendulum_lab.integrators.registry import METHODS

ONE_METHOD_PER_FAMILY = "--one-method-per-family"


def pytest_addoption(parser):
    parser.addoption(
        ONE_METHOD_PER_FAMILY, action="store_true",
        help="test the first registered member of each family of methods whose kernels are one "
             "code with other coefficients (the composition methods; the Gauss-Legendre "
             "methods), not the others (the floors job of make test)")


def same_code_as_a_tested_method() -> set[str]:
    """The registered methods after the first of their family: a composition method is the
    one kernel ``composed`` with other weights, a Gauss-Legendre method the one implicit
    tableau step with another tableau, so the first member exercises the libraries' code
    that the others would."""
    seen, others = set(), set()
    for name, method in METHODS.items():
        if method.composition is not None:
            family = "composition"
        elif method.tableau is not None and method.implicit:
            family = "implicit tableau"
        else:
            continue
        if family in seen:
            others.add(name)
        seen.add(family)
    return others


def methods_left_out(config) -> set[str]:
    """The registered methods this run does not test: none, or under
    ``--one-method-per-family`` the later members of each family."""
    return same_code_as_a_tested_method() if config.getoption(ONE_METHOD_PER_FAMILY) else set()


def pytest_collection_modifyitems(config, items):
    others = methods_left_out(config)
    if not others:
        return
    kept, dropped = [], []
    for item in items:
        params = getattr(getattr(item, "callspec", None), "params", {})
        names_another = any(isinstance(value, str) and value in others
                            for value in params.values())
        (dropped if names_another else kept).append(item)
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept


@pytest.fixture(scope="session")
def method_tested(request):
    """Whether this run tests a registered method: every one, but under
    ``--one-method-per-family`` not the later members of a family (for the loops inside a
    test, which the collection filter above cannot see)."""
    others = methods_left_out(request.config)
    return lambda name: name not in others


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


#: More memory than any refusal needs (checking 10**8 values takes 100 MB) and far less than
#: the arrays of the runs refused (gigabytes to tebibytes).
REFUSAL_MEMORY = 256 * 2**20


@pytest.fixture
def before_any_work(monkeypatch):
    """A context for a call that must be refused before any work: inside it, stepping a
    trajectory or drawing a figure fails the test, and so does holding more than
    :data:`REFUSAL_MEMORY` at once (NumPy's arrays count: it reports them to tracemalloc).

    The work is counted, not timed, so the check holds on a slow or busy machine (the floors
    run at the lowest priority) and fails on a fast one that did the work anyway."""
    from matplotlib.figure import Figure

    from pendulum_lab.driver.loops import CompiledMethod

    @contextlib.contextmanager
    def guard():
        done = []

        def refused(what):
            def work(*args, **kwargs):
                done.append(what)  # kept apart: the code under test might catch the error
                raise AssertionError(f"{what} before the refusal")
            return work

        with monkeypatch.context() as patch:
            patch.setattr(CompiledMethod, "advance", refused("a trajectory stepped"))
            patch.setattr(CompiledMethod, "step_rows", refused("a state stepped"))
            patch.setattr(Figure, "draw", refused("a figure drawn"))
            tracemalloc.start()
            try:
                yield
            finally:
                peak = tracemalloc.get_traced_memory()[1]
                tracemalloc.stop()
        assert not done, done
        assert peak < REFUSAL_MEMORY, f"{peak / 2**20:.0f} MiB held before the refusal"

    return guard
