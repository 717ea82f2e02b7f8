"""Rendered images made visible: depth in viridis, object ids in fixed bright colours, and any
uint8 image as PNG bytes (for logs, reporters' prompts and tests).

Apart from rendering because none of it needs OpenGL or MuJoCo: a depth or segmentation array
from anywhere (a rig, a saved ``.npz``) is coloured the same way.
"""

from __future__ import annotations

import io

import numpy as np

from capmj.errors import ConfigError

DEPTH_BACKGROUND = 4.99
"""Depth at or beyond which :func:`depth_to_visible` treats a pixel as "nothing seen" (far plane 5 m)."""

_VIRIDIS_ANCHORS = np.array([
    [68, 1, 84], [71, 44, 122], [59, 82, 139], [44, 113, 142], [33, 145, 140],
    [39, 173, 129], [92, 200, 99], [170, 220, 50], [253, 231, 37]], dtype=np.float64)
_VIRIDIS = np.stack([np.interp(np.linspace(0, 1, 256), np.linspace(0, 1, len(_VIRIDIS_ANCHORS)),
                               _VIRIDIS_ANCHORS[:, c]) for c in range(3)], axis=1).round().astype(np.uint8)
"""256-entry viridis approximation (9 anchors, linear in between)."""
_INVALID_RGB = np.array([40, 40, 40], np.uint8)


def depth_to_visible(depth: np.ndarray, near: float | None = None, far: float | None = None, *,
                     background: float = DEPTH_BACKGROUND) -> np.ndarray:
    """Colour a depth image (metres) with viridis: near = bright yellow, far = dark blue-purple.

    ``near``/``far`` default to the 1st/99th percentiles of the valid pixels, so the table and the
    objects use the whole colour range.  Pixels that are non-finite or at/after ``background`` are
    dark grey.  Returns uint8 (H, W, 3).  ``near > far`` is allowed (e.g. for heights:
    ``depth_to_visible(hm.height, near=0.1, far=0.0)`` makes tall things bright).
    """
    d = np.asarray(depth, dtype=np.float64)
    valid = np.isfinite(d) & (d < background)
    out = np.empty(d.shape + (3,), np.uint8)
    out[:] = _INVALID_RGB
    if not valid.any():
        return out
    vals = d[valid]
    lo = float(np.percentile(vals, 1)) if near is None else float(near)
    hi = float(np.percentile(vals, 99)) if far is None else float(far)
    span = hi - lo if hi != lo else 1e-6
    t = np.clip((vals - lo) / span, 0.0, 1.0)
    out[valid] = _VIRIDIS[np.round((1.0 - t) * 255).astype(np.int64)]
    return out


def seg_to_visible(seg: np.ndarray) -> np.ndarray:
    """Colour an object-id image: 0 black, every id its own fixed bright colour. uint8 (H, W, 3)."""
    ids = np.asarray(seg, dtype=np.int64)
    golden = (ids * 0.61803398875) % 1.0  # well-spread hues for consecutive ids
    h6 = golden * 6.0
    x = 1.0 - np.abs(h6 % 2.0 - 1.0)
    sector = np.floor(h6).astype(np.int64) % 6
    c, z = np.ones_like(x), np.zeros_like(x)
    table = [(c, x, z), (x, c, z), (z, c, x), (z, x, c), (x, z, c), (c, z, x)]
    rgb = np.zeros(ids.shape + (3,))
    for k, (r, g, b) in enumerate(table):
        sel = sector == k
        rgb[sel] = np.stack([r[sel], g[sel], b[sel]], axis=-1)
    out = (55 + 200 * rgb).astype(np.uint8)
    out[ids == 0] = 0
    return out


def to_png(array: np.ndarray) -> bytes:
    """Encode a uint8 image (H, W), (H, W, 3) or (H, W, 4) as PNG bytes (Pillow).

    Float depth images must be coloured first with :func:`depth_to_visible`.
    """
    from PIL import Image

    a = np.asarray(array)
    if a.dtype == np.bool_:
        a = a.astype(np.uint8) * 255
    if a.dtype != np.uint8:
        raise ConfigError(f"to_png needs a uint8 image, got {a.dtype}; colour depth with depth_to_visible()")
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))):
        raise ConfigError(f"to_png needs an (H, W), (H, W, 3) or (H, W, 4) image, got shape {a.shape}")
    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(a)).save(buf, format="PNG")
    return buf.getvalue()
