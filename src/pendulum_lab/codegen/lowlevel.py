"""Every place where pendulum_lab reaches below Numba's ordinary ``@njit`` code: one module.

The rest of the package is ordinary Numba code; what it cannot say in Numba's own language is
here, each device with what it buys (measured on the double pendulum, x86-64, Numba 0.68 and
llvmlite 0.50). Its tests pass with every minor release of Numba from 0.61 (llvmlite 0.44) to
0.68; ``pyproject.toml`` keeps Numba below its next minor version until that one is checked:

* **Views without a reference count** (:func:`span`, :func:`vector`, :func:`block`,
  :func:`unmanaged`): slices of a step's workspace. An ordinary slice is reference counted:
  every view and every argument passed on costs an atomic increment and decrement, several
  times the arithmetic of a small step. These views own nothing, so they must not outlive the
  array they point into (:func:`keep_alive` marks where it may be freed).
* **A stack buffer** (:func:`stack_floats`): the stage sums of an implicit Runge-Kutta step,
  accumulated where LLVM knows no other pointer reaches them, so that the loop over the stages
  vectorizes (glrk16's stage sums took half the time).
* **Bit casts** (:func:`float_bits`, :func:`bits_float`): the stopping rule takes maxima of
  non-negative floats as integers, which LLVM vectorizes and a floating-point maximum it would
  not (105 against 51 ns on 32 components, the rule deciding the same).
* **One ``sincos`` call** (:func:`sincos`): the sine and cosine of one angle from one call of
  the C library, sharing the argument reduction as a C compiler would; where the C library is
  glibc, an angle near ``+-pi`` is shifted by ``pi`` first, into its fast branch (the Kapitza
  pendulum held inverted: its cost per field evaluation 1.39-1.45 instead of 1.49-1.51 times
  the driven pendulum's, medians of benchmark item 15). Which C library that is depends on the
  operating system (:data:`HAVE_SINCOS`, ``docs/portability.md``).
* **Sines and cosines the compiler can vectorize** (:func:`lane_sin`, :func:`lane_cos`,
  :func:`lane_sincos`): the stage kernel of one or two links evaluates the field at 8 stages in
  one SIMD loop, which a call of the C library's ``sin`` would stop (LLVM cannot vectorize an
  opaque call, and the llvmlite wheels on PyPI are built without Intel's SVML patch, so Numba
  cannot vectorize ``math.sin`` even with the ``intel-cmplr-lib-rt`` runtime installed). With
  the C library's sines in the same loop, glrk16 and glrk12 runs of the double pendulum took
  2.0 to 2.2 times as long (1000 s from (2, 2.5)), which would lose the comparison with heyoka;
  so they stay, tested to two units in the last place (``tests/codegen/test_lowlevel.py``).
* **LLVM function attributes** (:func:`align_stack`, :func:`inline_into_callers`): a 64-byte
  aligned stack frame for the vectorized kernels (in some processes their 512-bit spills were
  split over cache lines: 100 against 160-170 ns per field evaluation), and inlining across
  compiled modules for functions called once per sweep (a glrk16 step 1.47 instead of 1.63 us
  with the stopping rule inlined, its run over 1000 s 37 instead of 43 ms with the ``stages``
  kernel inlined).

Tests check what each device does (results, bits, aliasing), never the machine code.
"""

from __future__ import annotations

import ctypes
import math
import sys

import llvmlite.ir as llvm_ir
import numba
from numba.core import cgutils, types
from numba.extending import intrinsic

__all__ = [
    "HAVE_SINCOS",
    "LANE_GROUP",
    "LIMIT",
    "SHIFTED_ULPS",
    "SHIFT_NEAR_PI",
    "c_library_has_sincos",
    "align_stack",
    "bits_float",
    "block",
    "float_bits",
    "inline_into_callers",
    "keep_alive",
    "lane_cos",
    "lane_sin",
    "lane_sincos",
    "sincos",
    "span",
    "stack_floats",
    "unmanaged",
    "vector",
]


# ------------------------------------------------------------------------- LLVM attributes
@intrinsic
def align_stack(typingctx):
    """Align the calling kernel's stack frame to 64 bytes.

    A loop vectorized with 512-bit registers spills some of them to the
    stack. Unless the function asks for an aligned frame before its registers
    are allocated, LLVM can only give the spill slots the 16-byte alignment
    that the calling convention guarantees, and then the speed depends on
    where the operating system happened to place the stack (in some
    processes each 64-byte spill was split over two cache lines; the cost is
    in the module docstring). The function's ``alignstack`` attribute makes
    its prologue realign the stack, so that every process gets the fast
    placement.
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
    module (what inlining them buys is in the module docstring). Numba cannot
    inline the stopping rule's round-off test itself, whose division rules
    (``error_model``) differ from its callers'; LLVM inlines the compiled
    function, rules included.
    """

    def codegen(context, builder, sig, args):
        builder.function.attributes.add("alwaysinline")
        return context.get_dummy_value()

    return types.none(), codegen


# ------------------------------------------------------------------------- bit casts
@intrinsic
def float_bits(typingctx, x):
    """The bits of a float64 as an int64: for ``x >= 0`` they order as ``x`` does."""
    def codegen(context, builder, sig, args):
        return builder.bitcast(args[0], context.get_value_type(types.int64))

    return types.int64(types.float64), codegen


@intrinsic
def bits_float(typingctx, bits):
    """The float64 whose bits are ``bits`` (the inverse of :func:`float_bits`)."""
    def codegen(context, builder, sig, args):
        return builder.bitcast(args[0], context.get_value_type(types.float64))

    return types.float64(types.int64), codegen


# ------------------------------------------------------------------------- views and buffers
@intrinsic
def _element_address(typingctx, array, index):
    """The address of ``array[index]`` (a 1-d contiguous array) as a typed pointer."""
    signature = types.CPointer(array.dtype)(array, index)

    def codegen(context, builder, sig, args):
        data = context.make_array(sig.args[0])(context, builder, args[0]).data
        return builder.gep(data, [args[1]])

    return signature, codegen


@numba.njit
def span(memory, start, length):
    """``memory[start : start + length]`` as a view without a reference count.

    The step functions carve their workspace out of ``memory`` with this.
    An ordinary slice is reference counted: each view and each argument
    passed on costs an atomic increment and decrement, several times the
    arithmetic of a small step; a reshape calls into Numba's runtime. This
    view points into ``memory``'s data and owns nothing, so it must not
    outlive ``memory`` (it never leaves the time loop), and ``memory`` must be
    named again after the view's last use if nothing else holds it (:func:`keep_alive`).
    """
    return numba.carray(_element_address(memory, start), length)


@numba.njit
def vector(memory, index, n):
    """The ``index``-th vector of ``n`` floats in ``memory`` (a :func:`span`)."""
    return span(memory, index * n, n)


@numba.njit
def unmanaged(array):
    """``array`` (1-d, contiguous) as a view without a reference count (see :func:`vector`)."""
    return numba.carray(_element_address(array, 0), array.size)


@numba.njit
def block(memory, start, rows, columns):
    """``memory[start:]`` as a C-ordered ``(rows, columns)`` array, a :func:`span` in 2-d."""
    return numba.carray(_element_address(memory, start), (rows, columns))


@numba.njit
def keep_alive(array):
    """Nothing: a use of ``array`` that keeps it alive up to this point.

    Numba frees an array after the last line that names it. A function that hands out views
    of an array it allocated (:func:`span`) must name the array again after the views' last
    use, or the memory may be given to another allocation while the views still point there.
    """


@intrinsic
def stack_floats(typingctx, count):
    """A float64 array of ``count`` (a literal) elements on the calling function's stack."""
    if not isinstance(count, types.IntegerLiteral):
        return None
    size = count.literal_value
    array_type = types.Array(types.float64, 1, "C")

    def codegen(context, builder, sig, args):
        buffer = cgutils.alloca_once(builder, llvm_ir.ArrayType(llvm_ir.DoubleType(), size))
        buffer.align = 64
        array = context.make_array(array_type)(context, builder)
        intp = context.get_value_type(types.intp)
        context.populate_array(array, data=builder.bitcast(buffer, array.data.type),
                               shape=[intp(size)], strides=[intp(8)], itemsize=intp(8),
                               meminfo=None)
        return array._getvalue()

    return array_type(count), codegen


# ------------------------------------------------------------------------- sine and cosine
def c_library_has_sincos(platform: str | None = None) -> bool:
    """Whether compiled kernels can call the C library's ``sincos`` on this operating system.

    ``sincos`` is a GNU extension, not standard C. Numba's JIT links a kernel's call of it
    against the symbols already loaded in the process (llvmlite searches the process, as
    ``dlsym`` does), so the test is whether the process has that symbol; a kernel that called
    a missing one would fail to link on its first call, long after the import.

    * Linux: glibc's (and musl's) libm has it, and every CPython process has libm loaded:
      ``ctypes.CDLL(None)`` opens the process's own symbols, the ones the JIT sees.
    * macOS: libSystem exports no ``sincos`` (its paired call is ``__sincos_stret``, returning
      a structure); the kernels call ``sin`` and ``cos`` separately, which LLVM's back end for
      Apple targets itself turns into one ``__sincos_stret`` call (per LLVM's code-generation
      tests; not measured here).
    * Windows: the Universal C Runtime has no ``sincos``, ``find_library("m")`` is None there
      and ``ctypes.CDLL(None)`` raises TypeError; the kernels call ``sin`` and ``cos``.

    Never raises: any failure to look means False, the separate calls, which are right on
    every system. ``platform`` defaults to ``sys.platform``.
    """
    platform = sys.platform if platform is None else platform
    if platform.startswith(("win32", "cygwin", "darwin")):
        return False
    try:
        process = ctypes.CDLL(None)
        return hasattr(process, "sincos")
    except (OSError, TypeError, AttributeError, ValueError):
        return False


#: Whether the kernels call the C library's ``sincos`` (:func:`c_library_has_sincos`: on Linux
#: yes, on macOS and Windows no). It also decides the shift near ``+-pi`` (:func:`sincos`),
#: which was measured against glibc's branches only.
HAVE_SINCOS = c_library_has_sincos()


@intrinsic
def _c_sincos(typingctx, x):
    """``(sin(x), cos(x))`` for a float ``x``, from one call of the C library's ``sincos``.

    The kernels need the sine and the cosine of the same angle differences
    (the mass matrix has ``cos(theta_i - theta_j)``, the forces
    ``sin(theta_i - theta_j)``); one call shares the argument reduction, as a C
    compiler arranges by itself (LLVM, behind Numba, does not). glibc's
    ``sincos`` returns exactly ``sin(x)`` and ``cos(x)``. Without :data:`HAVE_SINCOS`
    (macOS, Windows), ``llvm.sin`` and ``llvm.cos``: LLVM's back end turns them into the
    system's paired call where its table of C library functions lists one (glibc's
    ``sincos``: kernels compiled here with :data:`HAVE_SINCOS` forced off still call it;
    Apple's ``__sincos_stret``) and into two calls elsewhere, so it never names a symbol the
    process lacks.
    """
    if not isinstance(x, types.Float):
        return None
    signature = types.UniTuple(types.float64, 2)(types.float64)

    def codegen(context, builder, sig, args):
        double = llvm_ir.DoubleType()
        if HAVE_SINCOS:
            function = cgutils.get_or_insert_function(
                builder.module,
                llvm_ir.FunctionType(llvm_ir.VoidType(), [double, double.as_pointer(),
                                                          double.as_pointer()]),
                "sincos",
            )
            sine = cgutils.alloca_once(builder, double)
            cosine = cgutils.alloca_once(builder, double)
            builder.call(function, [args[0], sine, cosine])
            values = [builder.load(sine), builder.load(cosine)]
        else:
            values = [builder.call(builder.module.declare_intrinsic(name, [double]), args)
                      for name in ("llvm.sin", "llvm.cos")]
        return context.make_tuple(builder, sig.return_type, values)

    return signature, codegen


# glibc's sine and cosine reduce an argument above 2.426265 in a slower branch than below it.
# Angles near +-pi (an inverted pendulum, opposite links) are moved there by subtracting pi.
#: ``pi`` in two parts: the float nearest it and the rest, rounded (together to about 1e-32).
PI_1, PI_2 = 3.141592653589793, 1.2246467991473532e-16
#: ``sincos`` shifts ``|x|`` in this range by ``pi``: then ``|x - pi| < 0.855469``, glibc's
#: first branch, which needs no reduction.
SHIFT_FROM, SHIFT_TO = 2.426265, 3.997
#: Whether :func:`sincos` shifts at all: only with the C library whose branches were measured
#: (glibc, where :data:`HAVE_SINCOS`); elsewhere it gives the C library's own values throughout.
SHIFT_NEAR_PI = HAVE_SINCOS
#: The most the shifted values can differ from the exact sine and cosine, in units in the last
#: place: rounding ``x - pi`` costs up to half a unit of the argument, which is a whole unit of
#: a sine just below a power of two (``x - pi`` just beyond one), and the C library's own
#: rounding adds half a unit (measured against mpmath: 1.32, at ``x = 3.0165786637849092``,
#: ``tests/codegen/test_lowlevel.py``).
SHIFTED_ULPS = 1.5


@numba.njit(inline="always")
def sincos(x):
    """``(sin(x), cos(x))``: :func:`_c_sincos`, at ``x - pi`` where ``|x|`` is near ``pi``.

    There ``sin(x) = -sin(x - pi)`` and ``cos(x) = -cos(x - pi)``, and ``x - PI_1`` is exact
    (Sterbenz), so the shifted argument is ``x - pi`` rounded once: the values are within
    :data:`SHIFTED_ULPS` (1.5) units in the last place of the exact ones (1.32 measured), not
    always the C library's to the bit, and take 21 ns instead of 28 ns when each call waits for
    the last (docs/design/system-protocol.md). Elsewhere, and everywhere when
    :data:`SHIFT_NEAR_PI` is false (macOS, Windows), they are exactly the C library's.
    """
    if SHIFT_NEAR_PI and SHIFT_FROM <= abs(x) <= SHIFT_TO:
        sine, cosine = _c_sincos((x - math.copysign(PI_1, x)) - math.copysign(PI_2, x))
        return -sine, -cosine
    return _c_sincos(x)


# ------------------------------------------------------------------------- vectorizable sines
# How: ``x = k pi/2 + r`` with ``|r| <= pi/4`` (Cody and Waite's reduction, with
# ``pi/2`` split into three parts whose first two have 33 significant bits, so
# that ``k`` times them is exact for ``|k| < 2^20``), then the Taylor series of
# sine and cosine on ``[-pi/4, pi/4]``, kept up to the degree where the next
# term is below a few hundredths of a unit in the last place, and the quadrant
# ``k mod 4`` to pick and sign the results. The cosine adds ``1 - r^2/2`` in
# two parts, so that the rounding of that sum is not lost (as fdlibm's
# ``__kernel_cos`` does). Both agree with the C library to two units in the
# last place for ``|x| <= LIMIT`` (``tests/codegen/test_lowlevel.py``); larger
# arguments lose accuracy, and the stage kernels recompute such stages with
# the C library.
#: The stages of an implicit step are evaluated in groups of this many
#: (unused ones at the step's start): a ``stages`` kernel's loop is vectorized
#: 8 iterations at a time, whatever the SIMD width (2, 4 or 8 doubles,
#: interleaved), and a shorter loop stays scalar.
LANE_GROUP = 8

#: Arguments up to this size are reduced exactly enough (``k < 2^20``, with margin).
LIMIT = 1.0e5

TWO_OVER_PI = 0.6366197723675814
# pi/2 = HALF_PI_1 + HALF_PI_2 + HALF_PI_3 to 1e-37; the first two have 33 significant bits.
HALF_PI_1 = 1.5707963267341256  # 0x1.921fb544p+0
HALF_PI_2 = 6.077100506303966e-11  # 0x1.0b4611a6p-34
HALF_PI_3 = 2.0222662487959506e-21  # 0x1.3198a2e037073p-69
# Adding and subtracting 1.5 * 2^52 rounds a float below 2^51 to an integer (round to even).
ROUNDING = 6755399441055744.0

# 1/k! for the Taylor series; sine: k = 3, 5, ..., 17; cosine: k = 4, 6, ..., 16.
_S = tuple((-1.0) ** j / math.factorial(2 * j + 1) for j in range(1, 9))
_C = tuple((-1.0) ** j / math.factorial(2 * j) for j in range(2, 9))
S3, S5, S7, S9, S11, S13, S15, S17 = _S
C4, C6, C8, C10, C12, C14, C16 = _C


@numba.njit(inline="always")
def _reduced(x):
    """``(r, k)``: ``x = k pi/2 + r``, ``|r| <= pi/4``, ``k`` a whole number (as a float)."""
    k = (x * TWO_OVER_PI + ROUNDING) - ROUNDING
    return ((x - k * HALF_PI_1) - k * HALF_PI_2) - k * HALF_PI_3, k


@numba.njit(inline="always")
def _sine_cosine_near_zero(r):
    """``(sin r, cos r)`` for ``|r| <= pi/4``."""
    z = r * r
    sine_tail = S5 + z * (S7 + z * (S9 + z * (S11 + z * (S13 + z * (S15 + z * S17)))))
    sine = r + r * z * (S3 + z * sine_tail)
    cosine_tail = z * z * (C4 + z * (C6 + z * (C8 + z * (C10 + z * (C12 + z * (C14 + z * C16))))))
    half = 0.5 * z
    w = 1.0 - half
    cosine = w + (((1.0 - w) - half) + cosine_tail)
    return sine, cosine


@numba.njit(inline="always")
def lane_sincos(x):
    """``(sin x, cos x)``, vectorizable (module docstring); accurate for ``|x| <= LIMIT``."""
    r, k = _reduced(x)
    s, c = _sine_cosine_near_zero(r)
    quarter = k * 0.25
    quadrant = k - 4.0 * math.floor(quarter)  # k mod 4, as 0.0, 1.0, 2.0 or 3.0
    odd = (quadrant == 1.0) | (quadrant == 3.0)
    sine = c if odd else s
    cosine = s if odd else c
    sine = -sine if quadrant >= 2.0 else sine
    cosine = -cosine if (quadrant == 1.0) | (quadrant == 2.0) else cosine
    return sine, cosine


@numba.njit(inline="always")
def lane_sin(x):
    """``sin x``, vectorizable; accurate for ``|x| <= LIMIT``."""
    return lane_sincos(x)[0]


@numba.njit(inline="always")
def lane_cos(x):
    """``cos x``, vectorizable; accurate for ``|x| <= LIMIT``."""
    return lane_sincos(x)[1]
