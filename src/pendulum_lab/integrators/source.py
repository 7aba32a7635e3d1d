"""A method's step as the notebooks show it: its reference step, the formula in plain NumPy.

Each registered method carries a reference step (:attr:`Method.reference
<pendulum_lab.integrators.method.Method.reference>`, :mod:`pendulum_lab.integrators.reference`)
against which its compiled kernel is tested step by step; showing that source next to the
derivation keeps text, formula and tested code together.
"""

from __future__ import annotations

import functools
import inspect
import textwrap

from .composition import SUBSTEP_NAMES, Composition
from .registry import get_method
from .tableau import ButcherTableau

__all__ = ["method_source"]


def _code_names(code) -> list[str]:
    """Global names a code object uses, including those of nested functions and lambdas."""
    names = list(code.co_names)
    for const in code.co_consts:
        if inspect.iscode(const):
            names.extend(_code_names(const))
    return names


def _shown(name: str, key: str, value) -> str:
    """A bound argument as the header shows it."""
    if isinstance(value, ButcherTableau):
        return f"{key}=<the Butcher tableau of {name}, {value.stages} stages>"
    if isinstance(value, Composition):
        return f"{key}=<the {value.stages} substeps of {name}, below>"
    return f"{key}={value!r}"


def _binding(name: str, step: functools.partial) -> list[str]:
    """Comment lines saying which arguments a method's reference step has bound.

    A composition's substeps follow, one a line, with their source: they are the method.
    """
    bound = ", ".join(_shown(name, key, value) for key, value in step.keywords.items())
    lines = [f"# {name}: {step.func.__name__}(field, t, q, p, h, {bound})"]
    for value in step.keywords.values():
        if isinstance(value, Composition):
            lines += [f"#   {line}" for line in value.describe()]
            if value.source:
                lines += textwrap.wrap(f"weights from {value.source}", 88,
                                       initial_indent="#   ", subsequent_indent="#   ")
    return lines


def method_source(method, helpers: bool = False) -> str:
    """The source code of a method's reference step, the formula the compiled step is tested on.

    Notebooks show this next to the derivation. The compiled kernel
    (``Method.kernel``) computes the same step, to round-off, as the tests check step by
    step (``tests/integrators/test_reference_steps.py``); it is written for speed, this for
    reading.

    Parameters
    ----------
    method : str or Method
        A key of :data:`pendulum_lab.METHODS`, ``CONFORMAL_METHODS`` or
        ``VARIATIONAL_METHODS``, or a :class:`~pendulum_lab.integrators.method.Method`
        with a reference step.
    helpers : bool
        Also show the functions of the step's module that it calls (the symplectic step a
        conformal one composes, the fixed-point solver with its stopping rule), each once,
        in order of first use, after the step. By default only a last comment line names
        them: the step is the lesson, the solver's stopping rule is not.

    Returns
    -------
    str
        The step's source, preceded by a comment line naming the bound arguments when the
        step is a general one bound to the method's data (a Runge-Kutta method's tableau;
        a composition's substeps, one a line, and where its weights come from).

    Examples
    --------
    >>> print(method_source("explicit_euler"))  # doctest: +ELLIPSIS
    def explicit_euler(field, t, q, p, h):
        ...
        y1 = y + h * field.f(t, y)
    ...
    >>> print(method_source("leapfrog").splitlines()[-1])
    # It calls fixed_point, shown by method_source('leapfrog', helpers=True).
    """
    chosen = get_method(method)
    step = chosen.reference
    if step is None:
        raise ValueError(f"`method` {chosen.name!r} has no reference step to show")
    header, unused = [], set()
    if isinstance(step, functools.partial):
        header, step = _binding(chosen.name, step), step.func
        if chosen.composition is not None:  # the base maps this composition does not take
            used = {SUBSTEP_NAMES[kind] for kind, _ in chosen.composition.substeps}
            unused = set(SUBSTEP_NAMES.values()) - used
    found, queue = [step], [step]
    while queue:
        function = queue.pop(0)
        for name in _code_names(function.__code__):
            candidate = function.__globals__.get(name)
            if (inspect.isfunction(candidate) and candidate.__module__ == step.__module__
                    and candidate not in found and name not in unused):
                found.append(candidate)
                queue.append(candidate)
    shown = found if helpers else found[:1]
    text = "\n".join(header) + ("\n" if header else "") + "\n\n".join(
        inspect.getsource(function).rstrip() for function in shown) + "\n"
    if not helpers and len(found) > 1:
        names = [function.__name__ for function in found[1:]]
        names = " and ".join([", ".join(names[:-1]), names[-1]] if len(names) > 1 else names)
        text += (f"# It calls {names}, shown by method_source({chosen.name!r}, "
                 "helpers=True).\n")
    return text
