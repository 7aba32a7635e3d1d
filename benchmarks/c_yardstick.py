"""The RK4 loop in C, the yardstick for items 1, 5 and 7 (and item 6 itself).

The C source is generated at benchmark time from pendulum_lab's own SymPy
equations with SymPy's C code printer (``sympy.ccode``, common subexpressions
shared with ``sympy.cse``), compiled with ``gcc -O2 ... -lm`` into a temporary
folder and run as a separate program that times itself with ``clock_gettime``.
No binary is ever committed. Chains of one or two links, conservative or
forced (damping and drive), are supported: the double pendulum for items 1, 5
and 6, the damped, driven pendulum for item 8.

Which form of the equations
---------------------------
The Hamiltonian form, factored as pendulum_lab's compiled kernels factor it:
``dq = M(q)^-1 p`` (the mass matrix printed from ``chain.mass_matrix`` and
solved in closed form) and ``dp = dL/dq (+ Q)`` evaluated at ``omega = dq``
(printed from ``chain.dlagrangian_dq`` and, for a forced chain, the
generalized forces ``chain.generalized_forces``, which depend on the time).
RK4 runs on the canonical state ``(theta, p)``, exactly as
``pl.simulate(..., method="rk4")`` does, with the same stage times and the
same association of every floating-point sum, and the sine and cosine of one angle
from one ``sincos`` call moved by ``pi`` near ``+-pi`` where the kernels do so (Linux), from
``sin`` and ``cos`` where they do (macOS, Windows: ``lowlevel.sincos``), so the two
programs do the same arithmetic and their end states can be compared to round-off. Parameters are
read at run time (not compile-time constants), as the compiled kernels
receive them, so the compiler cannot fold them away.

The program (``P`` parameters, ``n`` links)::

    prog PAR_1 .. PAR_P single N_STEPS DT REPS THETA_1 .. THETA_n P_1 .. P_n
    prog PAR_1 .. PAR_P ensemble N_STEPS DT REPS INFILE OUTFILE

``single`` prints one ``seconds WALL cpu CPU`` line per repetition (each from the same
initial state, at t = 0) and the final state; ``ensemble`` reads ``K x 2n`` float64 rows
``(theta, p)``, advances every row ``N_STEPS`` steps one after the other on one
thread, and writes the final rows to ``OUTFILE``.
"""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sympy as sp

from pendulum_lab import codegen
from pendulum_lab.codegen import lowlevel

__all__ = ["CLoop", "CRun", "build", "c_source", "compiler_version"]

COMPILER = "gcc"
FLAGS = ("-O2",)


def _declarations(targets: list[str], exprs, mapping: dict, prefix: str, trig: dict) -> list[str]:
    """C statements ``target = expression;`` with common subexpressions shared.

    ``trig`` replaces the sines and cosines computed together beforehand, as
    the compiled kernels do (``codegen.paired_trig``).
    """
    exprs = [sp.sympify(e).xreplace(mapping).xreplace(trig) for e in exprs]
    temps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols(prefix))
    lines = [f"const double {t} = {sp.ccode(e)};" for t, e in temps]
    lines += [f"{t} = {sp.ccode(e)};" for t, e in zip(targets, reduced)]
    return lines


def c_source(chain) -> str:
    """The C program for a chain of one or two links (``pl.derive_chain(n, forced)``)."""
    n = chain.n
    if n not in (1, 2):
        raise ValueError(f"`chain` must have one or two links, got n = {n}")
    th = sp.symbols(f"th0:{n}", real=True)
    w = sp.symbols(f"w0:{n}", real=True)
    par = sp.symbols(f"par0:{len(chain.parameters)}", real=True)
    mapping = dict(zip(chain.q, th)) | dict(zip(chain.omega, w)) | dict(zip(chain.parameters, par))
    mapping[chain.t] = sp.Symbol("t", real=True)
    mass = chain.mass_matrix
    entries = {"m00": mass[0, 0]} if n == 1 else {"m00": mass[0, 0], "m01": mass[0, 1],
                                                  "m11": mass[1, 1]}
    rates = chain.dlagrangian_dq
    if chain.forced:  # damping and drive torques: dp = dL/dq + Q
        rates = rates + chain.generalized_forces
    # sin and cos of one angle from one sincos call, exactly as the kernels do
    pairs, trig = codegen.paired_trig(list(chain.mass_matrix) + list(rates), mapping)
    trig_lines = [f"double {s}, {c}; paired_sincos({sp.ccode(angle)}, &{s}, &{c});"
                  for s, c, angle in pairs]
    mass_lines = [f"double {name};" for name in entries]
    mass_lines += _declarations(list(entries), list(entries.values()), mapping, "a", trig)
    force_lines = _declarations([f"dp[{i}]" for i in range(n)], list(rates), mapping, "b", trig)
    lines = [*trig_lines, *mass_lines, "", *_solve_lines(n), "", *force_lines]
    body = "\n".join("    " + line if line else "" for line in lines)
    unpack = [f"const double th{i} = q[{i}];" for i in range(n)]
    unpack += [f"const double par{i} = PARAMS[{i}]; (void)par{i};" for i in range(len(par))]
    return (_TEMPLATE.replace("@HAMILTON_BODY@", body)
            .replace("@UNPACK@", "\n".join("    " + line for line in unpack))
            .replace("@N@", str(n)).replace("@NPAR@", str(len(par)))
            .replace("@PAIRED_WHAT@", _paired()[0])
            .replace("@PAIRED_BODY@", _paired()[1])
            .replace("@WHAT@", ("the driven, damped " if chain.forced else "the ")
                     + ("simple pendulum" if n == 1 else "double pendulum")))


#: What ``paired_sincos`` does, with and without the kernels' shift near pi, and its body.
_PAIRED = {
    True: ("near +-pi, the C library's sincos at x - pi, negated.", """\
    if (@SHIFT_FROM@ <= fabs(x) && fabs(x) <= @SHIFT_TO@) {
        sincos((x - copysign(@PI_1@, x)) - copysign(@PI_2@, x), s, c);
        *s = -*s;
        *c = -*c;
    } else {
        sincos(x, s, c);
    }"""),
    # macOS and Windows: no sincos in the C library, and the kernels do not shift
    False: ("the C library's sin and cos.", """\
    *s = sin(x);
    *c = cos(x);"""),
}


def _paired() -> tuple[str, str]:
    """What ``paired_sincos`` does and its body: the choice ``lowlevel.sincos`` makes on this
    system (``docs/portability.md``)."""
    what, body = _PAIRED[bool(lowlevel.SHIFT_NEAR_PI and lowlevel.HAVE_SINCOS)]
    return what, (body.replace("@SHIFT_FROM@", repr(lowlevel.SHIFT_FROM))
            .replace("@SHIFT_TO@", repr(lowlevel.SHIFT_TO))
            .replace("@PI_1@", repr(lowlevel.PI_1)).replace("@PI_2@", repr(lowlevel.PI_2)))


def _solve_lines(n: int) -> list[str]:
    # dq = M^-1 p in the closed form the compiled kernels use (Cramer's rule for n = 2).
    if n == 1:
        return ["dq[0] = p[0] / m00;", "const double w0 = dq[0];"]
    return [
        "const double det = m00 * m11 - m01 * m01;",
        "dq[0] = (m11 * p[0] - m01 * p[1]) / det;",
        "dq[1] = (m00 * p[1] - m01 * p[0]) / det;",
        "const double w0 = dq[0];",
        "const double w1 = dq[1];",
    ]


_TEMPLATE = r"""/* Generated by benchmarks/c_yardstick.py from pendulum_lab's SymPy equations.
   RK4 on @WHAT@ in canonical variables (theta, p). Do not edit. */
#define _GNU_SOURCE /* sincos */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define N @N@
#define NPAR @NPAR@

/* The chain's parameters, set at run time so that nothing is constant-folded. */
static double PARAMS[NPAR];

/* pendulum_lab.codegen.lowlevel.sincos as this system compiles it: @PAIRED_WHAT@ */
static inline void paired_sincos(double x, double *s, double *c)
{
@PAIRED_BODY@
}

static void hamilton(double t, const double *q, const double *p, double *dq, double *dp)
{
    (void)t;
@UNPACK@
@HAMILTON_BODY@
}

/* Classical RK4; stage times and every sum as in pendulum_lab's explicit_rk. */
static void rk4_step(double t, double *q, double *p, double h)
{
    double k1q[N], k1p[N], k2q[N], k2p[N], k3q[N], k3p[N], k4q[N], k4p[N], sq[N], sp[N];
    int m;
    hamilton(t, q, p, k1q, k1p);
    for (m = 0; m < N; ++m) { sq[m] = q[m] + h * 0.5 * k1q[m]; sp[m] = p[m] + h * 0.5 * k1p[m]; }
    hamilton(t + 0.5 * h, sq, sp, k2q, k2p);
    for (m = 0; m < N; ++m) { sq[m] = q[m] + h * 0.5 * k2q[m]; sp[m] = p[m] + h * 0.5 * k2p[m]; }
    hamilton(t + 0.5 * h, sq, sp, k3q, k3p);
    for (m = 0; m < N; ++m) { sq[m] = q[m] + h * k3q[m]; sp[m] = p[m] + h * k3p[m]; }
    hamilton(t + 1.0 * h, sq, sp, k4q, k4p);
    for (m = 0; m < N; ++m) {
        q[m] = q[m] + h * (1.0 / 6.0) * k1q[m] + h * (1.0 / 3.0) * k2q[m]
               + h * (1.0 / 3.0) * k3q[m] + h * (1.0 / 6.0) * k4q[m];
        p[m] = p[m] + h * (1.0 / 6.0) * k1p[m] + h * (1.0 / 3.0) * k2p[m]
               + h * (1.0 / 3.0) * k3p[m] + h * (1.0 / 6.0) * k4p[m];
    }
}

static double seconds_between(struct timespec a, struct timespec b)
{
    return (double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec);
}

static int usage(void)
{
    fprintf(stderr, "usage: prog PARAMS... single N_STEPS DT REPS THETA... P...\n"
                    "       prog PARAMS... ensemble N_STEPS DT REPS INFILE OUTFILE\n"
                    "(%d parameters, %d links)\n", NPAR, N);
    return 2;
}

int main(int argc, char **argv)
{
    struct timespec t0, t1, c0, c1;
    long n_steps, s, k;
    int reps, r, i;
    double h;
    const int a = 1 + NPAR; /* argv[a] is the mode */
    if (argc < a + 4) return usage();
    for (i = 0; i < NPAR; ++i) PARAMS[i] = atof(argv[1 + i]);
    n_steps = atol(argv[a + 1]);
    h = atof(argv[a + 2]);
    reps = atoi(argv[a + 3]);
    if (argv[a][0] == 's' && argc == a + 4 + 2 * N) {
        double y[2 * N];
        for (r = 0; r < reps; ++r) {
            for (i = 0; i < 2 * N; ++i) y[i] = atof(argv[a + 4 + i]);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
            clock_gettime(CLOCK_MONOTONIC, &t0);
            for (s = 0; s < n_steps; ++s) rk4_step((double)s * h, y, y + N, h);
            clock_gettime(CLOCK_MONOTONIC, &t1);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
            printf("seconds %.9e cpu %.9e\n", seconds_between(t0, t1), seconds_between(c0, c1));
        }
        printf("final");
        for (i = 0; i < 2 * N; ++i) printf(" %.17g", y[i]);
        printf("\n");
        return 0;
    }
    if (argv[a][0] == 'e' && argc == a + 6) {
        FILE *f = fopen(argv[a + 4], "rb");
        long size, rows;
        double *initial, *state;
        if (!f) { perror(argv[a + 4]); return 1; }
        fseek(f, 0, SEEK_END); size = ftell(f); fseek(f, 0, SEEK_SET);
        rows = size / (long)(2 * N * sizeof(double));
        initial = malloc((size_t)size); state = malloc((size_t)size);
        if (!initial || !state || fread(initial, sizeof(double), (size_t)(2 * N * rows), f)
                                      != (size_t)(2 * N * rows)) return 1;
        fclose(f);
        for (r = 0; r < reps; ++r) {
            for (k = 0; k < 2 * N * rows; ++k) state[k] = initial[k];
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
            clock_gettime(CLOCK_MONOTONIC, &t0);
            for (k = 0; k < rows; ++k) {
                double *y = state + 2 * N * k;
                for (s = 0; s < n_steps; ++s) rk4_step((double)s * h, y, y + N, h);
            }
            clock_gettime(CLOCK_MONOTONIC, &t1);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
            printf("seconds %.9e cpu %.9e\n", seconds_between(t0, t1), seconds_between(c0, c1));
        }
        f = fopen(argv[a + 5], "wb");
        if (!f || fwrite(state, sizeof(double), (size_t)(2 * N * rows), f)
                      != (size_t)(2 * N * rows))
            return 1;
        fclose(f);
        free(initial); free(state);
        return 0;
    }
    return usage();
}
"""


def compiler_version() -> str:
    """First line of ``gcc --version``, or ``"not found"``."""
    if shutil.which(COMPILER) is None:
        return "not found"
    out = subprocess.run([COMPILER, "--version"], capture_output=True, text=True,
                         encoding="utf-8", errors="replace", check=False)
    return out.stdout.splitlines()[0] if out.stdout else "unknown"


@dataclass(frozen=True)
class CLoop:
    """A compiled C RK4 loop for one chain of ``n`` links (parameters fixed at build)."""

    executable: Path
    source: Path
    params: tuple
    command: str
    n: int = 2

    def _run(self, args: list[str]) -> list[str]:
        out = subprocess.run(
            [str(self.executable), *map(repr, self.params), *args],
            capture_output=True,
            text=True,
            encoding="utf-8",
            errors="replace",
            check=False,
        )
        if out.returncode != 0:
            raise RuntimeError(f"C loop failed ({out.returncode}): {out.stderr.strip()}")
        return out.stdout.splitlines()

    def single(self, theta0, p0, n_steps: int, dt: float, reps: int = 1) -> CRun:
        """Run one trajectory ``reps`` times, each from ``(theta0, p0)`` (shape (n,) each)."""
        theta0 = np.asarray(theta0, float).reshape(self.n)
        p0 = np.asarray(p0, float).reshape(self.n)
        args = [str(int(n_steps)), repr(float(dt)), str(int(reps))]
        lines = self._run(["single", *args, *(repr(float(x)) for x in (*theta0, *p0))])
        final = np.array([float(x) for x in lines[-1].split()[1:]])
        return CRun(*_timings(lines), final[: self.n], final[self.n :])

    def ensemble(self, theta0, p0, n_steps: int, dt: float, reps: int = 1) -> CRun:
        """Run rows ``(theta0[k], p0[k])`` (shape (K, n) each) one after the other, one thread."""
        theta0 = np.asarray(theta0, float).reshape(-1, self.n)
        p0 = np.asarray(p0, float).reshape(-1, self.n)
        rows = np.ascontiguousarray(np.concatenate([theta0, p0], axis=1))
        infile = self.executable.with_name("ensemble_in.bin")
        outfile = self.executable.with_name("ensemble_out.bin")
        rows.tofile(infile)
        args = [str(int(n_steps)), repr(float(dt)), str(int(reps)), str(infile), str(outfile)]
        lines = self._run(["ensemble", *args])
        final = np.fromfile(outfile).reshape(-1, 2 * self.n)
        return CRun(*_timings(lines), final[:, : self.n], final[:, self.n :])


@dataclass(frozen=True)
class CRun:
    """What one call of the C program measured and computed.

    ``seconds`` (wall, CLOCK_MONOTONIC) and ``cpu`` (CLOCK_PROCESS_CPUTIME_ID)
    per repetition; ``theta`` and ``p`` the final state(s) of the last one.
    """

    seconds: list
    cpu: list
    theta: np.ndarray
    p: np.ndarray


def _timings(lines: list[str]) -> tuple[list, list]:
    timed = [line.split() for line in lines if line.startswith("seconds")]
    return [float(t[1]) for t in timed], [float(t[3]) for t in timed]


def build(model, workdir) -> CLoop:
    """Generate, write and compile the C loop for ``model`` (one or two links) in ``workdir``."""
    if shutil.which(COMPILER) is None:
        raise RuntimeError(f"`{COMPILER}` was not found: the C yardstick needs a C compiler")
    workdir = Path(workdir)
    stem = ("driven_" if model.forced else "") + ("sp_rk4" if model.n == 1 else "dp_rk4")
    source = workdir / f"{stem}.c"
    executable = workdir / stem
    source.write_text(c_source(model.chain), encoding="utf-8")
    command = [COMPILER, *FLAGS, "-o", str(executable), str(source), "-lm"]
    out = subprocess.run(command, capture_output=True, text=True, encoding="utf-8",
                         errors="replace", check=False)
    if out.returncode != 0:
        raise RuntimeError(f"compiling the C yardstick failed:\n{out.stderr}")
    params = tuple(float(x) for x in model.parameter_values.values())
    shown = " ".join([COMPILER, *FLAGS, "-o", executable.name, source.name, "-lm"])
    return CLoop(executable, source, params, shown, model.n)
