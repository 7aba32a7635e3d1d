"""A minimal PNG encoder for the explorers' frames.

The explorers send a new PNG to the browser on every update. Matplotlib
saves PNGs through PIL, which tries the five PNG row filters on every row;
on a plot (mostly flat colour) storing the rows unfiltered and deflating them
at level 1 is quicker and gives a smaller file (docs/design/explorer-redraw.md).
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

__all__ = ["png_bytes"]

_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    """A PNG chunk: length, type, data and the CRC of type and data."""
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png_bytes(rgba: np.ndarray) -> bytes:
    """A PNG of an RGBA image (uint8, shape ``(height, width, 4)``); RGB if it is opaque."""
    rgba = np.asarray(rgba, dtype=np.uint8)
    if rgba.ndim != 3 or rgba.shape[2] != 4:
        raise ValueError(f"`rgba` must have shape (height, width, 4), got {rgba.shape}")
    opaque = bool(rgba[..., 3].min() == 255)
    pixels = rgba[..., :3] if opaque else rgba
    height, width, channels = pixels.shape
    rows = np.zeros((height, 1 + width * channels), np.uint8)  # byte 0 of a row: filter "none"
    rows[:, 1:] = pixels.reshape(height, width * channels)
    colour_type = 2 if opaque else 6  # truecolour, or truecolour with alpha
    header = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)
    return b"".join(
        [
            _SIGNATURE,
            _chunk(b"IHDR", header),
            _chunk(b"IDAT", zlib.compress(rows.data, 1)),
            _chunk(b"IEND", b""),
        ]
    )
