"""``python -m pendulum_lab``: the same as the ``pendulum-lab`` command."""

from pendulum_lab.cli import main

raise SystemExit(main())
