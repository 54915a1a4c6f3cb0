"""Reading images and frame sequences: files and arrays in, checked grey images out;
images written with errors that name the file."""

from . import frames  # noqa: F401  (seahough.io.frames, as before the lazy imports)
from .images import memory_needed, read_image, to_gray, write_bytes, write_image

__all__ = ["read_image", "to_gray", "memory_needed", "write_image", "write_bytes"]
