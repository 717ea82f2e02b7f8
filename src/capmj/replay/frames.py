"""Camera images of an episode log as PNG files: ``python -m capmj.replay FILE --frames DIR``.

Depth is written twice: the 16-bit millimetre PNG (exact, for scripts; it looks black in ordinary
image viewers because table depths are ~1000 of 65535) and a colour-mapped 8-bit preview next to
it (``*_depth_pXXX_preview.png``, near = bright, no-return pixels black) for eyes.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from capmj.replay.reader import ReplayError, iter_images

PREVIEW_COLORMAP = "turbo"


def depth_preview(mm: np.ndarray) -> np.ndarray:
    """uint8 RGB colour map of a uint16 millimetre depth image, stretched over its valid range
    (2nd..98th percentile; zero and saturated pixels are black)."""
    from matplotlib import colormaps

    d = np.asarray(mm, dtype=np.float64)
    valid = (d > 0) & (d < 65535)
    out = np.zeros(d.shape + (3,), dtype=np.uint8)
    if not valid.any():
        return out
    lo, hi = np.percentile(d[valid], [2, 98])
    x = np.clip((hi - d) / max(hi - lo, 1.0), 0.0, 1.0)  # near = 1 (bright end of the map)
    rgb = (colormaps[PREVIEW_COLORMAP](x)[..., :3] * 255).astype(np.uint8)
    out[valid] = rgb[valid]
    return out


def _as_pil(data: Any) -> Any:
    from PIL import Image

    if isinstance(data, bytes):
        pil = Image.open(io.BytesIO(data))
        pil.load()
        return pil
    arr = np.asarray(data)
    if arr.dtype == np.uint16:
        return Image.fromarray(arr if arr.ndim == 2 else arr[..., 0])  # 16-bit greyscale PNG
    if arr.dtype.kind == "f":  # metres -> uint16 millimetres
        return Image.fromarray(np.clip(np.nan_to_num(arr * 1000), 0, 65535).astype(np.uint16))
    return Image.fromarray(arr.astype(np.uint8))


def export_frames(path: str | Path, out_dir: str | Path, *, preview: bool = True) -> list[Path]:
    """Write the file's camera images as PNG into ``out_dir`` (depth also as a colour preview);
    returns the written paths."""
    from PIL import Image

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ReplayError(f"cannot create {out}: {exc.strerror or exc}") from exc
    written: list[Path] = []
    seen: dict[str, int] = {}
    for img in iter_images(path):
        cam = img.entity[len("/camera/"):].rsplit("/", 1)[0].replace("/", "_") or "camera"
        p = f"p{img.primitive:03d}" if img.primitive is not None else "static"
        stem = f"{cam}_{img.kind}_{p}"
        seen[stem] = seen.get(stem, 0) + 1
        if seen[stem] > 1:
            stem += f"_{seen[stem]}"
        pil = _as_pil(img.data)
        target = out / f"{stem}.png"
        pil.save(target, format="PNG")
        written.append(target)
        if preview and img.kind == "depth" and pil.mode.startswith("I"):
            prev = out / f"{stem}_preview.png"
            Image.fromarray(depth_preview(np.asarray(pil))).save(prev, format="PNG")
            written.append(prev)
    return written


__all__ = ["PREVIEW_COLORMAP", "depth_preview", "export_frames"]
