"""The explorers' rough edges: orbits kept per energy, readouts that match the titles."""

import re

import pendulum_lab as pl
from pendulum_lab import widgets
from pendulum_lab.widgets.clickable import ENERGY_FORMAT, ENERGY_STEP

DP = pl.double_pendulum()


def title_energy(ex) -> str:
    """The energy the title of the section's picture states."""
    return re.search(r"E = (\S+) J", ex.plot.frame["title"]).group(1)


def test_the_energy_slider_keeps_the_orbits_of_each_energy_and_says_so():
    ex = widgets.section_explorer(DP, energy=-15.0, t_end=20.0)
    assert ex.click(0.5, 0.0) and ex.click(-0.3, 1.0)
    ex.controls["energy"].value = -10.0
    # The picture of the new energy holds none of them, and the message says where they are.
    assert ex.orbits == [] and ex.plot.orbits == []
    assert "2 at E = -15 J" in ex.message and "kept" in ex.message
    assert ex.click(0.2, 0.0)
    ex.controls["energy"].value = -15.0
    assert len(ex.orbits) == 2 and len(ex.plot.orbits) == 2
    assert "2 orbit(s) launched here before are shown" in ex.message
    assert "1 at E = -10 J" in ex.message
    # Clear removes the orbits shown only.
    ex.clear()
    ex.controls["energy"].value = -10.0
    assert len(ex.orbits) == 1


def test_the_energy_readout_shows_what_the_title_states():
    ex = widgets.section_explorer(DP, energy=-15.0, t_end=20.0)
    slider = ex.controls["energy"]
    # Every value the slider can take lies on its grid, so its readout is exact ...
    assert (slider.min / ENERGY_STEP).is_integer() and (slider.max / ENERGY_STEP).is_integer()
    for value in (slider.min, -14.5, slider.max):
        slider.value = value
        shown = format(slider.value, slider.readout_format)
        assert float(shown) == float(title_energy(ex)) == slider.value
    # ... where the former range, from -depth + 1 J, put its values off the grid: -14.93 J
    # read "-14.9" on the slider (the negative control of the check above).
    depth = -float(DP.potential_energy([0.0, 0.0]))
    off_grid = -depth + 1.0 + 25 * ENERGY_STEP
    assert float(format(off_grid, ENERGY_FORMAT)) != off_grid
