"""pytest hooks for running the course notebooks with nbval (``pytest --nbval-lax notebooks``).

Cells marked ``# NBVAL_CHECK_OUTPUT`` must reproduce their stored text output. Standard error is
left out of that comparison: warnings, progress bars and kernel messages written there depend on
the machine and on library versions, not on the results the notebooks teach. So are the notes
that a first-use compilation shows in a cell (``pendulum_lab.codegen.compile_status``): they
appear only where the kernel cache is empty, and the kernels nbval starts inherit the setting
that silences them. An exception in any cell still fails the run.
"""

import os


def pytest_collectstart(collector):
    """Skip stderr when nbval compares a notebook's outputs."""
    if collector.fspath and collector.fspath.ext == ".ipynb":
        collector.skip_compare += ("stderr",)
        os.environ.setdefault("PENDULUM_LAB_COMPILE_NOTES", "off")
