"""The application layer: the ``pendulum-lab`` command, the report study, warm-up and timing.

``cli`` (the command line), ``report`` (the course report's study, rerun), ``warmup``
(compiling what the course uses, ahead of time), ``timing`` (measurements the notebooks
print) and ``tables`` (Markdown tables).
"""
