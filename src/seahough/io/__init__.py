"""Reading images and frame sequences: files and arrays in, checked grey images out."""

from .images import read_image, to_gray

__all__ = ["read_image", "to_gray"]
