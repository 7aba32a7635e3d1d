"""Run notebooks under nbval as if their C library were another system's (docs/portability.md).

Usage::

    .venv/bin/python tools/emulate_c_library.py without-sincos notebooks/11_*.ipynb
    .venv/bin/python tools/emulate_c_library.py other-library notebooks/17_*.ipynb

``without-sincos`` hides ``sincos`` from ``codegen.lowlevel``'s detection, as on macOS and
Windows (no shift near pi). ``other-library`` binds, in Numba's symbol table, a sine and cosine
that differ from the C library's by one unit in the last place at about half of the arguments
(odd and even to the bit, exact at 0); it needs a C compiler (``gcc``). Either way the
notebooks' kernels compile into empty caches of their own, and nbval compares the checked
outputs with the stored ones: a failure names a checked output that depends on the last bits.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

WITHOUT_SINCOS = """\
import ctypes

_real = ctypes.CDLL


class _WithoutSincos(_real):
    def __getattr__(self, name):
        if name == "sincos":
            raise AttributeError(name)
        return super().__getattr__(name)


ctypes.CDLL = _WithoutSincos
"""

OTHER_LIBRARY_C = r"""
#include <math.h>
#include <stdint.h>
#include <string.h>

/* One unit in the last place up or down at about half of the arguments, by a hash of |x|. */
static double nudge(double x, double value, uint64_t salt)
{
    uint64_t b;
    if (x == 0.0 || !isfinite(value)) return value;
    memcpy(&b, &x, 8);
    b ^= salt;
    b ^= b >> 31; b *= 0xbf58476d1ce4e5b9ULL; b ^= b >> 29; b *= 0x94d049bb133111ebULL;
    b ^= b >> 32;
    if (b & 1) return nextafter(value, (b & 2) ? INFINITY : -INFINITY);
    return value;
}
double other_sin(double x)
{
    double s = nudge(fabs(x), sin(fabs(x)), 0x5151);
    return x < 0 ? -s : s;
}
double other_cos(double x) { return nudge(fabs(x), cos(fabs(x)), 0xc0c0); }
void other_sincos(double x, double *s, double *c) { *s = other_sin(x); *c = other_cos(x); }
"""

OTHER_LIBRARY = """\
import ctypes

import llvmlite.binding as _binding
from numba.core import externals as _externals

_library = ctypes.CDLL({library!r})


def _bind():
    for name in ("sin", "cos", "sincos"):
        address = ctypes.cast(getattr(_library, "other_" + name), ctypes.c_void_p).value
        _binding.add_symbol(name, address)


_install = _externals._ExternalMathFunctions._do_install


def _do_install(self, context):
    _install(self, context)  # Numba binds the C library's sin and cos here; bind ours after
    _bind()


_externals._ExternalMathFunctions._do_install = _do_install
_bind()
"""


def prepare(kind: str, folder: Path) -> str | None:
    """Write the emulation's ``sitecustomize.py`` into ``folder``; a reason if it cannot."""
    if kind == "without-sincos":
        text = WITHOUT_SINCOS
    else:
        compiler = shutil.which("gcc") or shutil.which("cc")
        if compiler is None:
            return "no C compiler (gcc or cc) to build the other library"
        source, library = folder / "other_library.c", folder / "libother_library.so"
        source.write_text(OTHER_LIBRARY_C, encoding="utf-8")
        built = subprocess.run([compiler, "-O2", "-shared", "-fPIC", "-o", str(library),
                                str(source), "-lm"], capture_output=True, text=True,
                               encoding="utf-8", errors="replace", check=False)
        if built.returncode != 0:
            return f"the other library did not compile: {built.stderr.strip()[-500:]}"
        text = OTHER_LIBRARY.format(library=str(library))
    (folder / "sitecustomize.py").write_text(text, encoding="utf-8")
    return None


#: Run under the emulation before the notebooks: it fails unless the emulation took effect.
IN_EFFECT = {
    "without-sincos": "from pendulum_lab.codegen import lowlevel; assert not lowlevel.HAVE_SINCOS",
    "other-library": (
        "import math, numba, numpy as np\n"
        "xs = np.linspace(0.1, 10.0, 1001)\n"
        "sine = numba.njit(lambda xs: np.array([math.sin(x) for x in xs]))(xs)\n"
        "assert 0.3 < np.mean(sine != np.array([math.sin(x) for x in xs])) < 0.7"
    ),
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("kind", choices=["without-sincos", "other-library"])
    parser.add_argument("notebooks", nargs="+", type=Path)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="pendulum_lab_emulation_") as temporary:
        folder = Path(temporary)
        reason = prepare(args.kind, folder)
        if reason is not None:
            print(f"emulate_c_library: {reason}", file=sys.stderr)
            return 2
        path = os.pathsep.join([str(folder), str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])
        env = os.environ | {"PYTHONPATH": path.rstrip(os.pathsep),
                            "PENDULUM_LAB_CACHE": str(folder / "kernels"),
                            "NUMBA_CACHE_DIR": str(folder / "numba")}
        if subprocess.call([sys.executable, "-c", IN_EFFECT[args.kind]], cwd=ROOT, env=env):
            print("emulate_c_library: the emulation did not take effect", file=sys.stderr)
            return 2
        command = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q",
                   *map(str, args.notebooks)]
        return subprocess.call(command, cwd=ROOT, env=env)


if __name__ == "__main__":
    sys.exit(main())
