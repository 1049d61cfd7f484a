"""Blender Images ↔ flat pixel lists. Blender keeps rows bottom to top; volstyle (and EXR) top to
bottom. Views are float, linear Images: the artist paints them with Texture Paint."""
from __future__ import annotations

import bpy

try:  # Blender ships numpy (Debian's Blender: python3-numpy); per-pixel Python loops otherwise
    import numpy as np
except ImportError:
    np = None


def linear(image) -> None:
    """Marks a float Image as linear data (Blender 3.x calls it 'Linear', 4.x 'Linear Rec.709')."""
    for name in ("Linear Rec.709", "Linear"):
        try:
            image.colorspace_settings.name = name
            return
        except TypeError:
            continue


def image_from_rgb(name: str, width: int, height: int, rgb: list, alpha: float = 1.0, hidden: bool = False):
    """A float RGBA Image (made or reused) holding `rgb` (top-to-bottom rows, 3 values a pixel)."""
    full = ("." if hidden else "") + name
    image = bpy.data.images.get(full)
    if image is not None and (image.size[0], image.size[1]) != (width, height):
        bpy.data.images.remove(image)
        image = None
    if image is None:
        image = bpy.data.images.new(full, width, height, alpha=True, float_buffer=True)
    linear(image)
    if np is not None:
        a = np.empty((height, width, 4), np.float32)
        a[..., :3] = np.asarray(rgb, np.float32).reshape(height, width, 3)[::-1]
        a[..., 3] = alpha
        image.pixels.foreach_set(a.ravel())
    else:
        rgba = [0.0] * (4 * width * height)
        for y in range(height):
            src, dst = 3 * (height - 1 - y) * width, 4 * y * width
            for x in range(width):
                rgba[dst + 4 * x:dst + 4 * x + 3] = rgb[src + 3 * x:src + 3 * x + 3]
                rgba[dst + 4 * x + 3] = alpha
        image.pixels.foreach_set(rgba)
    image.update()
    image.use_fake_user = True  # kept in the .blend even while no editor shows it
    return image


def rgba_of(image) -> list:
    """An Image's pixels as RGBA, rows top to bottom."""
    w, h = image.size
    if np is not None:
        a = np.empty(4 * w * h, np.float32)
        image.pixels.foreach_get(a)
        return a.reshape(h, w, 4)[::-1].ravel().tolist()
    flat = [0.0] * (4 * w * h)
    image.pixels.foreach_get(flat)
    out = [0.0] * (4 * w * h)
    for y in range(h):
        out[4 * y * w:4 * (y + 1) * w] = flat[4 * (h - 1 - y) * w:4 * (h - y) * w]
    return out
