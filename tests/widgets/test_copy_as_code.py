""""Copy as code": the code an instrument offers computes the very run its picture shows."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import animation, widgets
from pendulum_lab.widgets.calls import SimulateCall, model_code


def run_code(code: str) -> dict:
    """Run ``code`` as a student's fresh cell would; return its variables."""
    namespace: dict = {}
    exec(compile(code, "<copied>", "exec"), namespace)  # noqa: S102 - the code under test
    return namespace


def assert_same_run(ours, theirs):
    for name in ("t", "theta", "omega", "p", "energy"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(theirs, name), err_msg=name)
    assert ours.method == theirs.method and ours.dt == theirs.dt


def test_the_explorers_code_reproduces_its_run_after_changes():
    ex = widgets.explore(pl.double_pendulum(), t_end=3.0, method="rk4")
    assert ex.set_controls({"theta1": 0.73, "omega2": -1.15, "m2": 0.35, "l1": 1.4,
                            "g": 9.5, "dt": 0.005, "method": "glrk4"})
    code = ex.code()
    assert code == ex.status.code  # what the button copies
    assert "pl.simulate(model, [0.73, 2.5], [0.0, -1.15]" in code and "'glrk4'" in code
    assert_same_run(run_code(code)["traj"], ex.trajectory)


def test_a_changed_number_in_the_code_gives_another_run():
    # Negative control of the comparison: the check would see a wrong dt or state.
    ex = widgets.explore(pl.double_pendulum(), t_end=3.0, method="rk4")
    for before, after in (("dt=0.01", "dt=0.005"), ("[2.0, 2.5]", "[2.0, 2.5000001]")):
        changed = run_code(ex.code().replace(before, after))["traj"]
        with pytest.raises(AssertionError):
            assert_same_run(changed, ex.trajectory)


@pytest.mark.parametrize("build", [widgets.live_simulator, animation.simulator],
                         ids=["live", "matplotlib"])
def test_the_simulators_code_reproduces_a_driven_run(build):
    sim = build(pl.driven_pendulum(drive_amplitude=1.35), [0.4], [0.2], t_end=6.0, method="rk4")
    copied = run_code(sim.code())
    assert copied["model"].damping == (0.5,) and copied["model"].drive_amplitude == 1.35
    assert_same_run(copied["traj"], sim.trajectory)


def test_the_live_simulators_code_follows_a_drag():
    sim = widgets.live_simulator(pl.double_pendulum(), t_end=3.0)
    assert sim.drag(1, 0.3, -2.7, theta=[0.4, 0.1])
    assert_same_run(run_code(sim.code())["traj"], sim.trajectory)


def test_the_equilibrium_and_energy_explorers_code_reproduces_their_runs():
    near = widgets.explore_equilibrium(pl.double_pendulum(), "up-down", t_end=3.0,
                                       offset=[0.02, -0.01])
    assert_same_run(run_code(near.code())["traj"], near.trajectory)
    level = widgets.explore_energy(pl.double_pendulum(), energy=-12.3, t_end=4.0, method="rk4")
    assert_same_run(run_code(level.code())["traj"], level.trajectory)


def test_the_section_explorers_code_gives_the_crossings_drawn():
    ex = widgets.section_explorer(pl.double_pendulum(m2=0.8), energy=-15.0, t_end=30.0)
    assert ex.status.code == "" and ex.code() == ""  # nothing launched: nothing to copy
    assert ex.click(0.4, 0.7)
    copied = run_code(ex.code())
    theta2, p2 = copied["theta2"], copied["p2"]
    np.testing.assert_array_equal(np.column_stack([theta2, p2]), ex.orbits[0].points[1:])
    np.testing.assert_array_equal(copied["traj"].theta[0], np.ravel(copied["theta0"]))
    # (The driver recomputes omega(0) from p(0) = M omega0: equal to round-off.)
    np.testing.assert_allclose(copied["traj"].omega[0], np.ravel(copied["omega0"]), rtol=1e-15)
    assert ex.status.code == ex.code()
    ex.undo()
    assert ex.status.code == ""


def test_the_portrait_explorers_code_gives_the_curve_drawn():
    ex = widgets.portrait_explorer(pl.simple_pendulum(length=0.8), t_end=5.0, method="leapfrog")
    assert ex.click(-2.5, 3.0)
    copied = run_code(ex.code())
    np.testing.assert_array_equal(np.column_stack([copied["theta"], copied["omega"]]),
                                  ex.orbits[0].points)


@pytest.mark.parametrize("model", [
    pl.simple_pendulum(mass=0.3, length=1.7, g=3.71),
    pl.driven_pendulum(damping=0.0, drive_amplitude=0.7),
    pl.double_pendulum(m1=0.1 + 0.2, damping=[0.1, 0.05]),
    pl.double_pendulum(drive_amplitude=0.4, drive_frequency=1.3),
    pl.n_pendulum(3, masses=[1.0, 0.5, 0.25], lengths=[1.0, 0.9, 0.8], damping=0.2),
], ids=["simple", "undamped drive", "two dampings", "driven double", "three links"])
def test_model_code_builds_the_same_model(model):
    again = run_code("import pendulum_lab as pl\nmodel = " + model_code(model))["model"]
    assert repr(again) == repr(model)
    call = SimulateCall(model, np.full(model.n, 0.3), np.zeros(model.n), t_end=0.5, dt=0.01,
                        method="rk4")
    assert_same_run(run_code(call.code())["traj"], call.run())


def last_value(code: str):
    """What a pasted cell shows: the value of its last line if that is an expression."""
    import ast

    tree = ast.parse(code)
    namespace: dict = {}
    *body, last = tree.body
    exec(compile(ast.Module(body, []), "<copied>", "exec"), namespace)  # noqa: S102
    if not isinstance(last, ast.Expr):
        exec(compile(ast.Module([last], []), "<copied>", "exec"), namespace)  # noqa: S102
        return None
    return eval(compile(ast.Expression(last.value), "<copied>", "eval"), namespace)  # noqa: S307


def drawn(figure) -> int:
    """Axes of ``figure`` that hold data (lines, points, patches)."""
    return sum(bool(ax.lines or ax.collections or ax.patches) for ax in figure.axes)


@pytest.mark.parametrize("build", [
    lambda: widgets.explore(pl.double_pendulum(), t_end=2.0, method="rk4"),
    lambda: widgets.explore(pl.simple_pendulum(), t_end=2.0, method="rk4",
                            plots=("energy", "angles", "phase")),
    lambda: widgets.explore_equilibrium(pl.double_pendulum(), "up-down", t_end=2.0,
                                        offset=[0.02, -0.01]),
    lambda: widgets.explore_energy(pl.double_pendulum(), energy=-12.3, t_end=2.0, method="rk4"),
    lambda: widgets.explore_energy(pl.simple_pendulum(), energy=-5.0, t_end=2.0, method="rk4"),
    lambda: widgets.live_simulator(pl.double_pendulum(), t_end=2.0, method="rk4"),
    lambda: animation.simulator(pl.driven_pendulum(), [0.4], [0.2], t_end=2.0, method="rk4"),
], ids=["explore", "explore-3-panels", "equilibrium", "energy", "energy-1", "live",
        "matplotlib"])
def test_the_copied_code_draws_the_run_as_its_last_value(build):
    from matplotlib.figure import Figure

    instrument = build()
    code = instrument.code()
    figure = last_value(code)
    assert isinstance(figure, Figure) and drawn(figure) >= 1
    assert drawn(figure) == len(figure.axes)  # no empty axes left over
    # negative control: the call alone computes the run and draws nothing
    assert last_value(instrument.call.code()) is None


def test_a_students_own_panel_is_named_in_the_copied_code():
    def my_panel(ax, traj, model):
        ax.plot(traj.t, traj.theta[:, 0])

    ex = widgets.explore(pl.simple_pendulum(), t_end=1.0, method="rk4",
                         plots=("energy", my_panel))
    code = ex.code()
    assert "panels = [pl.plotting.PANELS['energy'], my_panel]" in code
    namespace = {"my_panel": my_panel}
    exec(compile(code, "<copied>", "exec"), namespace)  # noqa: S102
    assert drawn(namespace["fig"]) == 2


def test_the_clickable_explorers_code_draws_what_they_show():
    portrait = widgets.portrait_explorer(pl.simple_pendulum(), t_end=2.0, method="rk4")
    assert portrait.click(0.5, 0.0)
    assert drawn(last_value(portrait.code())) == 1
    section = widgets.section_explorer(pl.double_pendulum(m2=0.8), energy=-15.0, t_end=10.0)
    assert section.click(0.4, 0.7)
    assert drawn(last_value(section.code())) == 1
