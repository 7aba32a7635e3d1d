"""The source code of a method's step, as the library runs it.

Notebooks show it next to the derivation, so text and code cannot drift apart.
"""

from __future__ import annotations

import inspect

from .registry import get_method

__all__ = ["method_source"]


def _python_function(obj):
    """The Python function behind a compiled (Numba) or wrapped callable."""
    obj = getattr(obj, "py_func", obj)
    return inspect.unwrap(obj) if callable(obj) else obj


def _code_names(code) -> list[str]:
    """Global names a code object uses, including those of nested functions."""
    names = list(code.co_names)
    for const in code.co_consts:
        if inspect.iscode(const):
            names.extend(_code_names(const))
    return names


def method_source(method, helpers: bool = True) -> str:
    """The source code of a method's one-step function, as the library runs it.

    Notebooks show this next to the derivation, so text and code cannot drift
    apart.

    Parameters
    ----------
    method : str or Method
        A key of :data:`pendulum_lab.METHODS`.
    helpers : bool
        Also append the source of the functions of the integrators that the
        step calls (the Runge-Kutta stage loop, the fixed-point stopping
        rule), each once, in order of first use.

    Returns
    -------
    str

    Examples
    --------
    >>> "def leapfrog_step" in method_source("leapfrog")
    True
    """
    main = _python_function(get_method(method).kernel)
    found, queue = [main], [main]
    while helpers and queue:
        fn = queue.pop(0)
        for name in _code_names(fn.__code__):
            candidate = _python_function(fn.__globals__.get(name))
            if (inspect.isfunction(candidate) and candidate.__module__.startswith(__package__)
                    and candidate not in found):
                found.append(candidate)
                queue.append(candidate)
    return "\n\n".join(inspect.getsource(fn).rstrip() for fn in found) + "\n"
