"""The codegen layer: the symbolic equations printed as compiled Numba kernels.

``kernels`` prints a chain's (or any mechanical system's) SymPy expressions as the kernels
``hamilton``, ``acceleration`` and ``stages`` (and the discrete Legendre transforms of the
variational methods); ``cache`` writes generated code into the kernel cache under a key of
all the code it depends on; ``long_chains`` evaluates chains of any length link by link
instead; ``signatures`` fixes the calling convention of every kernel; ``lowlevel`` is the one
module that reaches below ordinary Numba code (with the sines and cosines the vectorized
``stages`` kernel uses).
"""

from .cache import cache_dir, code_key, load_generated
from .kernels import (
    UNROLLED_MAX_LINKS,
    discrete_kernel_source,
    import_name,
    kernel_source,
    load_discrete_kernels,
    load_kernels,
    load_system_kernels,
    looped_kernels,
    paired_trig,
    parameters_array,
    solve_spd,
    stage_kernel,
)
from .lowlevel import sincos

__all__ = [
    "UNROLLED_MAX_LINKS",
    "cache_dir",
    "code_key",
    "discrete_kernel_source",
    "import_name",
    "kernel_source",
    "load_discrete_kernels",
    "load_generated",
    "load_kernels",
    "load_system_kernels",
    "looped_kernels",
    "paired_trig",
    "parameters_array",
    "sincos",
    "solve_spd",
    "stage_kernel",
]
