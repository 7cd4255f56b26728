"""Raw camera frames (sensor_msgs/Image fields) to pictures, the size a viewer gets, and JPEG encoding.

Pillow does the work: its wheels bundle libjpeg-turbo (a 1280x720 frame encodes in about 5 ms here, a resize
to phone width adds about 8 ms), and it is already a dependency, so no second imaging stack (OpenCV) is needed.
"""
from __future__ import annotations

import io
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from PIL import Image

# bytes per pixel of each encoding shown (sensor_msgs/image_encodings names)
BYTES_PER_PIXEL = {"rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1, "8UC1": 1, "mono16": 2, "16UC1": 2}
SHOWN = ", ".join(BYTES_PER_PIXEL)
WIDTH_STEP = 160      # widths are rounded up to this, so viewers of about the same size share one encoding
MIN_WIDTH = 16
MAX_WIDTH = 7680      # before the camera's own width is known
DEFAULT_QUALITY = 70
QUALITY_STEP = 10


class FrameError(ValueError):
    """A frame that cannot be shown; the message says why, for the viewer."""


def picture(encoding: str, width: int, height: int, step: int, data: Any, bigendian: bool = False) -> Image.Image:
    """One sensor_msgs/Image as an RGB or grey picture. 16-bit images (depth) are shown grey, near dark and far
    light, scaled to the frame's own range; 0 (no reading) is black."""
    bpp = BYTES_PER_PIXEL.get(encoding)
    if bpp is None:
        raise FrameError(f"unsupported encoding {encoding or '(none)'} (shown: {SHOWN})")
    if width <= 0 or height <= 0:
        raise FrameError(f"empty frame ({width}x{height})")
    row = width * bpp
    if step < row or len(data) < step * height:
        raise FrameError(f"frame size does not match its header: {len(data)} bytes for {width}x{height} {encoding} "
                         f"with rows of {step} bytes")
    buf = np.frombuffer(bytes(data) if not isinstance(data, (bytes, bytearray, memoryview)) else data,
                        dtype=np.uint8, count=step * height).reshape(height, step)[:, :row]
    if bpp == 2:
        v = buf.copy().view(">u2" if bigendian else "<u2").reshape(height, width).astype(np.float32)
        seen = v[v > 0]
        lo, hi = (float(seen.min()), float(seen.max())) if seen.size else (0.0, 1.0)
        grey = np.where(v > 0, 40 + 215 * (v - lo) / max(hi - lo, 1.0), 0)
        return Image.fromarray(grey.astype(np.uint8))
    if bpp == 1:
        return Image.fromarray(np.ascontiguousarray(buf))
    px = buf.reshape(height, width, bpp)[:, :, :3]
    if encoding.startswith("bgr"):
        px = px[:, :, ::-1]
    return Image.fromarray(np.ascontiguousarray(px))


@dataclass(frozen=True)
class Size:
    width: int
    quality: int


def wanted(width: int, quality: int) -> Size:
    """What a request asks for, in shared steps: width rounded up to WIDTH_STEP (0: the camera's own), quality to
    QUALITY_STEP within 10..100 (0: the default)."""
    w = 0 if width <= 0 else min(MAX_WIDTH, max(WIDTH_STEP, math.ceil(width / WIDTH_STEP) * WIDTH_STEP))
    q = DEFAULT_QUALITY if quality <= 0 else min(100, max(10, round(quality / QUALITY_STEP) * QUALITY_STEP))
    return Size(w, q)


def frame_size(want: Size, source: tuple[int, int]) -> tuple[int, int]:
    """The frames' size for a wanted width from a source of (width, height): never larger than the source."""
    sw, sh = source
    w = sw if want.width <= 0 else max(min(MIN_WIDTH, sw), min(sw, want.width))
    return w, max(1, round(sh * w / sw))


def jpeg(img: Image.Image, size: tuple[int, int], quality: int) -> bytes:
    if img.size != size:
        img = img.resize(size, Image.BILINEAR, reducing_gap=2.0)
    out = io.BytesIO()
    img.save(out, format="JPEG", quality=quality)
    return out.getvalue()
