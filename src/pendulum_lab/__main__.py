"""``python -m pendulum_lab``: the same as the ``pendulum-lab`` command."""

from pendulum_lab.app.cli import main

if __name__ == "__main__":  # importing the module (as the API reference does) runs nothing
    raise SystemExit(main())
