"""Image size from the file's header, before any pixel is decoded (image bombs).

A PNG of a few kB can declare 100 000 x 100 000 pixels; decoding it asks for 30 GB.
:func:`check_image_pixels` reads only the header (Pillow's lazy ``Image.open``) and refuses an
image above :data:`MAX_IMAGE_PIXELS` with a :class:`VideoError` naming the file, so OpenCV
never sees it. Documented in docs/reference/protocols.md (Size limits).
"""

from __future__ import annotations

import warnings
from pathlib import Path

from labkit.errors import VideoError

#: 100 megapixels: above every camera a rig would use (a 4K frame is 8.3 MP).
MAX_IMAGE_PIXELS = 100_000_000


def check_image_pixels(path: str | Path, limit: int = MAX_IMAGE_PIXELS) -> tuple[int, int]:
    """``(width, height)`` from the header; VideoError if unreadable or above ``limit`` pixels."""
    from PIL import Image, UnidentifiedImageError

    name = str(path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Pillow's own bomb warning: we decide below
            with Image.open(name) as img:
                width, height = img.size
    except Image.DecompressionBombError:
        raise VideoError(name, f"image declares far more pixels than the limit of {limit} "
                               "(an image bomb?); refused before decoding") from None
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError):
        raise VideoError(name, "cannot be read as an image (unknown or corrupt format)") from None
    if width * height > limit:
        raise VideoError(name, f"image is {width} x {height} = {width * height} pixels, more than the "
                               f"limit of {limit} (an image bomb?); refused before decoding")
    return width, height
