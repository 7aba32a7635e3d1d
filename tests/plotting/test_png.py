"""The explorers' PNG encoder: its files decode to exactly the pixels given."""

import io

import numpy as np
import pytest
from PIL import Image

from pendulum_lab.plotting.png import png_bytes


@pytest.mark.parametrize("opaque", [True, False])
def test_png_bytes_decode_to_the_same_pixels(opaque):
    rng = np.random.default_rng(1)
    rgba = rng.integers(0, 256, size=(7, 5, 4), dtype=np.uint8)
    if opaque:
        rgba[..., 3] = 255
    image = Image.open(io.BytesIO(png_bytes(rgba)))
    assert image.mode == ("RGB" if opaque else "RGBA")
    expected = rgba[..., :3] if opaque else rgba
    assert np.array_equal(np.asarray(image), expected)
    # negative control: one changed pixel is seen
    other = rgba.copy()
    other[3, 2, 0] ^= 1
    assert not np.array_equal(np.asarray(Image.open(io.BytesIO(png_bytes(other)))), expected)


def test_png_bytes_rejects_a_non_rgba_array():
    with pytest.raises(ValueError, match="`rgba` must have shape"):
        png_bytes(np.zeros((4, 4, 3), dtype=np.uint8))
