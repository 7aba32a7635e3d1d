"""Items 11 and 12: the strongest peers for long accurate runs, heyoka and pyhamsys, side by side.

Item 11, long accurate runs against heyoka: for each energy requirement
(``cfg.peer_requirements``) at ``T = cfg.peer_t_end``, heyoka's loosest
tolerance that meets it (tolerances tried in half-decades) against our
fastest symplectic method at its largest passing step (searched, as item 3
does); then both at the same settings over ``cfg.peer_long_t_end``, with the
energy error of the first and the last tenth of each run: heyoka's drifts;
ours has no drift from the method (it is symplectic), only the slower growth
of rounding errors at these tight settings.

Item 12, against pyhamsys (Tao's extended phase space, its default scheme
BM4 and projection) at equal energy error: pyhamsys at ``cfg.pyhamsys_step``
over ``cfg.pyhamsys_t_end``; ours at the largest step whose error is no
larger. Then the composition methods against pyhamsys' same schemes
(:data:`PYHAMSYS_SCHEMES`), the same way: pyhamsys' scheme in Tao's explicit
extension, ours in its implicit leapfrog or symplectic Euler substeps. Both
optional: a missing peer gives a row that says so.
"""

from __future__ import annotations

import math

import numpy as np
import peers
import stage_solvers
from harness import (
    THETA0,
    Config,
    Row,
    Sample,
    Section,
    explorer_start,
    fmt_time,
    interleave,
    max_relative_energy_error,
    med,
    timed,
    verdict,
)
from item_long_run import _largest_passing

import pendulum_lab as pl

#: Methods tried for "our fastest symplectic method".
OURS = ("glrk8", "glrk12", "glrk16")
#: Our composition methods and pyhamsys' names of the same schemes (its ``Yo4`` is Yoshida's
#: triple jump, ``Yos6`` his solution A, ``M4`` McLachlan's, ``PEFRL`` Omelyan's).
PYHAMSYS_SCHEMES = {"yoshida4": "Yo4", "yoshida6": "Yos6", "mclachlan4": "M4",
                    "omelyan4": "PEFRL", "blanes_moan4": "BM4"}


def _our_runner(dp, theta0, omega0):
    def run(method, dt, t_end):
        sample, traj = timed(pl.simulate, dp, theta0, omega0, t_end=t_end, dt=dt,
                             method=method, progress=False)
        return traj, sample

    def evaluate(method, dt, t_end):
        traj, sample = run(method, dt, t_end)
        return max_relative_energy_error(traj.energy), {"seconds": sample.cpu}

    return run, evaluate


def _fastest_ours(cfg, evaluate, requirement, t_end, methods, details):
    """Per method the largest passing dt (pilot + search); the cheapest method wins."""
    found = {}
    for method in methods:
        order = pl.METHODS[method].order
        pilot_dt = cfg.peer_pilot_dt
        err, _ = evaluate(method, pilot_dt, cfg.long_pilot_t_end)
        guess = pilot_dt * (requirement / max(err, 1e-300)) ** (1 / order) * 0.9
        best, trials = _largest_passing(lambda dt, m=method: evaluate(m, dt, t_end), guess,
                                        order, requirement, precision=1.04, max_trials=8)
        details.append(
            f"{method} for <= {requirement:g} at T = {t_end:g} (dt: error, CPU s): "
            + "; ".join(f"{x:.4g}: {e:.3g}, {extra['seconds']:.3f}" for x, e, extra in trials)
        )
        if best is not None:
            found[method] = {"dt": best[0], "error": best[1], "seconds": best[2]["seconds"]}
    return found


def _heyoka_runner(dp, theta0, omega0):
    """``run(tol, t_end) -> (error, Sample)``: heyoka integrators built once per tolerance."""
    integrators = {}
    y0 = np.concatenate([theta0, omega0])

    def run(tol, t_end, grid_step):
        if tol not in integrators:
            integrators[tol] = peers.heyoka_integrator(dp, theta0, omega0, tol)
        ta = integrators[tol]
        grid = np.arange(0, round(t_end / grid_step) + 1) * grid_step

        def integrate():
            ta.time = 0.0
            ta.state[:] = y0
            outcome = ta.propagate_grid(grid)
            run.steps = int(outcome[3])  # the Taylor steps taken
            states = outcome[-1]
            return dp.energy(states[:, :2], states[:, 2:])

        sample, energy = timed(integrate)
        return max_relative_energy_error(energy), sample, ta.order, energy

    run.steps = 0
    return run


def _stage_solver_study(cfg, dp, theta0, p0, method, dt, requirement, budget) -> str:
    """Evaluations per step under other stage solvers, against what matching heyoka allows.

    ``budget``: the field evaluations (at our measured cost per evaluation)
    one step could spend for our run to take heyoka's time.
    """
    tableau = pl.METHODS[method].tableau
    counts = stage_solvers.evaluations_per_step(dp, theta0, p0, tableau, dt,
                                                cfg.stage_study_t_end)
    found = "; ".join(f"{name} {count:.1f}" if count > 0 else f"{name}: did not converge"
                      for name, count in counts.items())
    return (
        f"Stage solvers for <= {requirement:g} ({method}, dt = {dt:.4g}, "
        f"T = {cfg.stage_study_t_end:g}; field evaluations per step, the Jacobian's included; "
        f"`stage_solvers.py`): {found}. Matching heyoka's time allows {budget:.1f} per step, "
        f"{budget / tableau.stages:.1f} sweeps of the {tableau.stages} stages."
    )


def bench_heyoka(cfg: Config) -> Section:
    """Long accurate runs: ours (fastest symplectic) against heyoka's cheapest passing tolerance."""
    hy, reason = peers.heyoka_or_reason()
    title = "11. Long accurate runs vs heyoka"
    if hy is None:
        rows = [Row("11", f"T={cfg.peer_t_end:g}, energy <= {r:g}", "-", "heyoka: not installed",
                    "-", "-", "not available") for r in cfg.peer_requirements]
        return Section("heyoka", title, rows, [reason], {})
    dp, theta0, omega0, p0 = explorer_start()
    run_ours, evaluate = _our_runner(dp, theta0, omega0)
    run_heyoka = _heyoka_runner(dp, theta0, omega0)
    T, grid = cfg.peer_t_end, cfg.peer_grid
    rows, data = [], {"heyoka_version": hy.__version__, "requirements": {}}
    details = [
        f"Double pendulum from theta = {THETA0} at rest, T = {T:g} s. heyoka {hy.__version__}: "
        f"`taylor_adaptive` on (theta, omega) from our SymPy equations (`heyoka.from_sympy`), "
        f"`propagate_grid` on a {grid:g} s grid; energies on that grid included in its time; "
        "building the integrator (LLVM compilation, once per process) not timed, as our "
        "compiled loop's first load is not. Ours: `pl.simulate` with energies at every step. "
        "Requirement: max relative energy error <= the target over the whole run."
    ]
    for method in OURS:
        run_ours(method, 0.1, 1.0)  # load the compiled loops
    for requirement in cfg.peer_requirements:
        tols, chosen = [], None
        for k in range(cfg.heyoka_tol_steps):
            tol = 10.0 ** (-math.log10(1 / requirement) - k / 2)
            err, sample, order, _ = run_heyoka(tol, T, grid)
            tols.append((tol, err, sample.cpu, order))
            if err <= requirement:
                chosen = (tol, order)
                break
        details.append(
            f"heyoka for <= {requirement:g} (tol: error, CPU s, order): "
            + "; ".join(f"{t:.2g}: {e:.3g}, {c:.3f}, {o}" for t, e, c, o in tols)
        )
        found = _fastest_ours(cfg, evaluate, requirement, T, OURS, details)
        if chosen is None or not found:
            rows.append(Row("11", f"T={T:g}, max rel. energy error <= {requirement:g}", "-", "-",
                            "-", "-", "MISS (no passing setting found)"))
            continue
        best = min(found, key=lambda m: found[m]["seconds"])
        dt, tol = found[best]["dt"], chosen[0]
        last = {}

        def ours(best=best, dt=dt, last=last):
            traj, sample = run_ours(best, dt, T)
            last["ours"] = max_relative_energy_error(traj.energy)
            last["work"] = (len(traj.t) - 1, traj.evaluations, traj.mean_iterations)
            return sample

        def peer(tol=tol, last=last):
            err, sample, _, _ = run_heyoka(tol, T, grid)
            last["heyoka"] = err
            return sample

        samples = interleave({"ours": ours, "heyoka": peer}, cfg.peer_rounds)
        t_ours, t_peer = med(samples["ours"]), med(samples["heyoka"])
        steps, evaluations, sweeps = last["work"]
        details.append(
            f"Where the time goes for <= {requirement:g}: {best} takes {steps} steps of "
            f"{evaluations / steps:.1f} field evaluations each ({sweeps:.2f} sweeps of the "
            f"{pl.METHODS[best].tableau.stages} stages per step, to round-off), {evaluations} in "
            f"all, {t_ours / evaluations * 1e9:.0f} ns per evaluation with the loop; heyoka takes "
            f"{run_heyoka.steps} Taylor steps of order {chosen[1]}, "
            f"{t_peer / max(run_heyoka.steps, 1) * 1e6:.2f} us each."
        )
        details.append(_stage_solver_study(cfg, dp, theta0, p0, best, dt, requirement,
                                           t_peer / steps / (t_ours / evaluations)))
        ratio = t_ours / t_peer
        limit = cfg.peer_targets.get(requirement, 1.0)
        rows.append(Row(
            "11", f"T={T:g}, max rel. energy error <= {requirement:g}",
            f"{best} dt={dt:.4g}: {fmt_time(t_ours)} CPU (err {last['ours']:.2g})",
            f"heyoka tol={tol:.2g} (order {chosen[1]}): {fmt_time(t_peer)} CPU "
            f"(err {last['heyoka']:.2g})",
            f"{ratio:.2f}x", f"ours/heyoka <= {limit:g} (CPU)", verdict(ratio, limit),
        ))
        for method, v in found.items():
            if method != best:
                rows.append(Row("11", f"  other method for <= {requirement:g}: {method}",
                                f"dt={v['dt']:.4g}: {fmt_time(v['seconds'])} (search run)",
                                "-", f"{v['seconds'] / t_peer:.2f}x", "-", "info"))
        entry = {"method": best, "dt": dt, "heyoka_tol": tol, "ours_cpu": t_ours,
                 "heyoka_cpu": t_peer, "ratio": ratio, "ours_error": last["ours"],
                 "heyoka_error": last["heyoka"], "found": found}
        # The same settings over a longer run: how each energy error grows.
        long_T = cfg.peer_long_t_end
        try:
            traj, sample_ours = run_ours(best, dt, long_T)
        except pl.ConvergenceError as error:
            # A step that passed over T may still be too long later in the longer run.
            rows.append(Row("11", f"T={long_T:g}, same settings (req. {requirement:g} at T={T:g})",
                            str(error), "-", "-", "(report)", "info"))
            data["requirements"][str(requirement)] = entry
            continue
        energy = np.asarray(traj.energy)
        ours_rel = np.abs(energy - energy[0]) / abs(energy[0])
        err_h, sample_h, _, energy_h = run_heyoka(tol, long_T, grid)
        heyoka_rel = np.abs(energy_h - energy_h[0]) / abs(energy_h[0])
        tail_ours = float(ours_rel[ours_rel.size * 9 // 10:].max())
        tail_h = float(heyoka_rel[heyoka_rel.size * 9 // 10:].max())
        head_ours = float(ours_rel[: ours_rel.size // 10].max())
        head_h = float(heyoka_rel[: heyoka_rel.size // 10].max())
        rows.append(Row(
            "11", f"T={long_T:g}, same settings (req. {requirement:g} at T={T:g})",
            f"{best}: {fmt_time(sample_ours.cpu)}, err first/last tenth "
            f"{head_ours:.2g}/{tail_ours:.2g}",
            f"heyoka: {fmt_time(sample_h.cpu)}, err first/last tenth {head_h:.2g}/{tail_h:.2g}",
            f"{sample_ours.cpu / sample_h.cpu:.2f}x", "(report)", "info",
        ))
        entry["long"] = {"T": long_T, "ours_cpu": sample_ours.cpu, "heyoka_cpu": sample_h.cpu,
                         "ours_first_tenth": head_ours, "ours_last_tenth": tail_ours,
                         "heyoka_first_tenth": head_h, "heyoka_last_tenth": tail_h}
        data["requirements"][str(requirement)] = entry
    details.append(f"Timed: {cfg.peer_rounds} interleaved rounds, medians of CPU time.")
    return Section("heyoka", title, rows, details, data)


def bench_pyhamsys(cfg: Config) -> Section:
    """pyhamsys (Tao's method, default BM4) against ours at equal energy error."""
    module, reason = peers.pyhamsys_or_reason()
    title = "12. Equal energy error vs pyhamsys"
    if module is None:
        return Section("pyhamsys", title, [Row("12", "pyhamsys at equal energy error", "-",
                                               "pyhamsys: not installed", "-", "-",
                                               "not available")], [reason], {})
    dp, theta0, omega0, p0 = explorer_start()
    T, step = cfg.pyhamsys_t_end, cfg.pyhamsys_step
    run_ours, evaluate = _our_runner(dp, theta0, omega0)
    last = {}

    def peer():
        sample, sol = timed(peers.pyhamsys_run, dp, theta0, p0, T, step)
        energy = dp.hamiltonian_value(sol.y[: dp.n].T, sol.y[dp.n:].T)
        last["pyhamsys"] = max_relative_energy_error(energy)
        return Sample(sample.wall, sample.cpu)

    peer()  # loads the kernel; sets the error to match
    requirement = last["pyhamsys"]
    details = [
        f"pyhamsys {getattr(module, '__version__', '')}: `solve_ivp_sympext` (Tao's extended "
        f"phase space, default scheme BM4, default projection) at step {step:g} over T = {T:g} "
        f"from theta = {THETA0} at rest, vector field = our compiled Hamiltonian kernel (the "
        f"fastest right-hand side we can give it); its max relative energy error "
        f"{requirement:.3g} is the requirement for ours (fastest of leapfrog, glrk4, glrk8)."
    ]
    for method in ("leapfrog", "glrk4", "glrk8"):
        run_ours(method, 0.1, 1.0)
    found = _fastest_ours(cfg, evaluate, requirement, T, ("leapfrog", "glrk4", "glrk8"),
                          details)
    if not found:
        return Section("pyhamsys", title, [Row("12", "pyhamsys at equal energy error", "-", "-",
                                               "-", "-", "MISS (no passing setting)")],
                       details, {})
    best = min(found, key=lambda m: found[m]["seconds"])
    dt = found[best]["dt"]

    def ours():
        traj, sample = run_ours(best, dt, T)
        last["ours"] = max_relative_energy_error(traj.energy)
        return sample

    samples = interleave({"ours": ours, "pyhamsys": peer}, cfg.peer_rounds)
    t_ours, t_peer = med(samples["ours"]), med(samples["pyhamsys"])
    ratio = t_peer / t_ours
    rows = [Row(
        "12", f"T={T:g}, equal energy error ({requirement:.2g})",
        f"{best} dt={dt:.4g}: {fmt_time(t_ours)} CPU (err {last['ours']:.2g})",
        f"pyhamsys BM4 step={step:g}: {fmt_time(t_peer)} CPU (err {last['pyhamsys']:.2g})",
        f"{ratio:.0f}x faster", "peer/ours > 1 (CPU)", verdict(ratio, 1.0, at_most=False),
    )]
    data = {"method": best, "dt": dt, "ours_cpu": t_ours, "pyhamsys_cpu": t_peer,
            "ratio": ratio, "requirement": requirement, "found": found}
    rows += _composition_rows(cfg, dp, theta0, p0, run_ours, evaluate, details, data)
    details.append(f"Timed: {cfg.peer_rounds} interleaved rounds, medians of CPU time.")
    return Section("pyhamsys", title, rows, details, data)


def _composition_rows(cfg, dp, theta0, p0, run_ours, evaluate, details, data) -> list:
    """Each composition of :data:`PYHAMSYS_SCHEMES` against pyhamsys' same scheme."""
    T, step = cfg.pyhamsys_t_end, cfg.pyhamsys_step
    rows, data["compositions"] = [], {}

    def converging(method, dt, t_end):
        # a step too large for the implicit substeps fails the requirement, as a large error does
        try:
            return evaluate(method, dt, t_end)
        except pl.ConvergenceError:
            return math.inf, {"seconds": math.inf}
    for ours_name, scheme in PYHAMSYS_SCHEMES.items():
        last = {}

        def peer(scheme=scheme, last=last):
            sample, sol = timed(peers.pyhamsys_run, dp, theta0, p0, T, step, solver=scheme)
            energy = dp.hamiltonian_value(sol.y[: dp.n].T, sol.y[dp.n:].T)
            last["pyhamsys"] = max_relative_energy_error(energy)
            return Sample(sample.wall, sample.cpu)

        peer()
        requirement = last["pyhamsys"]
        run_ours(ours_name, 0.01, 0.1)  # compiles it outside the timing
        found = _fastest_ours(cfg, converging, requirement, T, (ours_name,), details)
        label = f"T={T:g}, {ours_name} vs pyhamsys {scheme} ({requirement:.2g})"
        if not found:
            rows.append(Row("12", label, "-", "-", "-", "-", "MISS (no passing setting)"))
            continue
        dt = found[ours_name]["dt"]

        def ours(name=ours_name, dt=dt, last=last):
            traj, sample = run_ours(name, dt, T)
            last["ours"] = max_relative_energy_error(traj.energy)
            return sample

        samples = interleave({"ours": ours, "pyhamsys": peer}, cfg.peer_rounds)
        t_ours, t_peer = med(samples["ours"]), med(samples["pyhamsys"])
        ratio = t_peer / t_ours
        rows.append(Row(
            "12", label,
            f"{ours_name} dt={dt:.4g}: {fmt_time(t_ours)} CPU (err {last['ours']:.2g})",
            f"pyhamsys {scheme} step={step:g}: {fmt_time(t_peer)} CPU "
            f"(err {last['pyhamsys']:.2g})",
            f"{ratio:.0f}x faster", "peer/ours > 1 (CPU)", verdict(ratio, 1.0, at_most=False),
        ))
        data["compositions"][ours_name] = {"scheme": scheme, "dt": dt, "ours_cpu": t_ours,
                                           "pyhamsys_cpu": t_peer, "ratio": ratio,
                                           "requirement": requirement}
    details.append("Compositions: pyhamsys' scheme in Tao's explicit extended phase space at "
                   f"step {step:g}; ours, the same weights on implicit substeps, at the largest "
                   "step whose max relative energy error is no larger.")
    return rows
