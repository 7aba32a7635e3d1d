"""Two attributes the compiled kernels give themselves for LLVM, by calling a no-op.

Numba offers no way to set an LLVM function attribute; these intrinsics set
one on the function that calls them, when it is compiled:

* :func:`align_stack`: the function realigns its stack frame to 64 bytes;
* :func:`inline_into_callers`: LLVM inlines the function wherever it is called
  from compiled code that links it (Numba's own ``inline="always"`` works on
  its IR instead, and only between functions compiled with the same options).

Generated code is named after this file's contents too
(:func:`pendulum_lab.codegen.load_generated`), so that a change here
recompiles what uses it.
"""

from __future__ import annotations

from numba.core import types
from numba.extending import intrinsic

__all__ = ["align_stack", "inline_into_callers"]


@intrinsic
def align_stack(typingctx):
    """Align the calling kernel's stack frame to 64 bytes.

    A loop vectorized with 512-bit registers spills some of them to the
    stack. Unless the function asks for an aligned frame before its registers
    are allocated, LLVM can only give the spill slots the 16-byte alignment
    that the calling convention guarantees, and then the speed depends on
    where the operating system happened to place the stack: the double
    pendulum's 8-column field took 100 ns in some processes and 160-170 ns
    in others (each 64-byte spill split over two cache lines). The function's
    ``alignstack`` attribute makes its prologue realign the stack, so that
    every process gets the fast placement.
    """

    def codegen(context, builder, sig, args):
        attributes = builder.function.attributes
        attributes.alignstack = 64
        # llvmlite prints ``alignstack`` only beside another attribute; Numba's
        # functions return errors as values and never unwind
        attributes.add("nounwind")
        return context.get_dummy_value()

    return types.none(), codegen


@intrinsic
def inline_into_callers(typingctx):
    """Mark the calling function ``alwaysinline``.

    For functions called once per sweep of an implicit step with several
    arrays, each passed as seven or nine values: the stopping rule
    (``integrators.fixed_point_status``), which LLVM's cost model kept a
    call, and the fields' ``stages`` kernels, which live in another compiled
    module. Inlined, a ``glrk16`` step took 1.47 instead of 1.63 us (the
    stopping rule) and its run over 1000 s 37 instead of 43 ms (the
    ``stages`` kernel), measured. Numba cannot inline the stopping rule's
    round-off test itself, whose division rules (``error_model``) differ from
    its callers'; LLVM inlines the compiled function, rules included.
    """

    def codegen(context, builder, sig, args):
        builder.function.attributes.add("alwaysinline")
        return context.get_dummy_value()

    return types.none(), codegen
