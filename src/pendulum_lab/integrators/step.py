"""How a method's one-step map is declared, so that the time loop can compile it with any field.

A step function has the signature ``(first_kernel, second_kernel, t, q, p, h, params, separable,
damping_rate[, memory]) -> (q1, p1, sweeps, calls)`` (see :mod:`pendulum_lab.integrators`). It
is never compiled alone: :mod:`pendulum_lab.driver.loops` compiles it inside the time loop of
each field it integrates, where the field's kernels are known and their calls are direct.
"""

from __future__ import annotations

import functools

import numba

__all__ = ["Step", "jit_step", "kernel_function"]


#: Decorator of every function that receives a kernel (``hamilton``,
#: ``acceleration``, a step) as an argument. Such a function is compiled into
#: each field's time loop (:mod:`pendulum_lab.driver.loops`), where the kernels are
#: known: inlined there, its kernel calls are direct calls. (A Numba function
#: compiled on its own with a kernel argument would hold a pointer to a Python
#: object, which Numba cannot keep in its disk cache.) Helpers that take no
#: kernel are plain ``numba.njit``: LLVM inlines them when the loop is linked,
#: while Numba's own inlining copies the callee's IR at every call site, which
#: makes compiling the loops slower (docs/design/compiled-loop.md).
kernel_function = numba.njit(inline="always")


class Step:
    """A method's step function, compiled into the time loop of each field it integrates.

    Make one with :func:`jit_step`. ``py_func`` is the Python source;
    ``memory(n)`` the floats the step keeps per trajectory for a state of
    ``n`` coordinates (0: the step takes no ``memory`` argument);
    ``compiled`` the Numba function the time loop calls, always with a
    ``memory`` argument. The generated time loops are cached under a key of
    the step's code and constants (:func:`pendulum_lab.codegen.cache.code_key`).
    """

    def __init__(self, py_func, memory=None):
        functools.update_wrapper(self, py_func)
        self.py_func = py_func
        self.memory = memory if memory is not None else (lambda n: 0)
        inner = kernel_function(py_func)
        if memory is None:  # the loop passes memory to every step; this one ignores it

            def ignores_memory(hamilton, acceleration, t, q, p, h, params, separable,
                               damping_rate, memory):
                return inner(hamilton, acceleration, t, q, p, h, params, separable,
                             damping_rate)

            self.compiled = kernel_function(ignores_memory)
        else:
            self.compiled = inner

    def __call__(self, *args):
        return self.py_func(*args)


def jit_step(py_func=None, *, memory=None):
    """Declare a step function (see the module docstring): ``@jit_step`` or ``@jit_step(memory=f)``.

    ``memory(n)`` is the number of floats the step keeps per trajectory for a
    state of ``n`` coordinates; a step declared with it takes the ``memory``
    argument last.
    """
    if py_func is None:
        return lambda fn: Step(fn, memory)
    return Step(py_func, memory)
