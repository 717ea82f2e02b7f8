"""Naming colours: CIELAB distances to the palette as each camera would see it.

A rendered surface facing up is not its albedo: the lights scale it (by about 1.1–1.25 here, a
little differently per camera because the headlight follows the camera) and bright channels clip
at 255.  Comparing raw pixels with the palette therefore confuses white with silver and gold with
yellow.  Instead each camera's gain is measured on the table, whose albedo is the one colour a
real robot calibrates against (:data:`TABLE_RGB`, the ``workspace`` geom of ``mjcf/table.xml``),
and every palette colour is predicted as ``clip(gain * albedo)`` for that camera.  Pixels are
then named by the nearest prediction in CIELAB, the space where Euclidean distance tracks
perceived difference (CIE76 ΔE).  The palette is the benchmark's (:mod:`capmj.sim.palette`):
names only, no scene state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from capmj.sim.palette import COLOR_NAMES, COLORS

TABLE_RGB: tuple[float, float, float] = (0.55, 0.5, 0.45)
"""Albedo of the table top (``mjcf/table.xml``, geom ``workspace``): the white-balance target."""

PALETTE_RGB: np.ndarray = np.array([COLORS[n][:3] for n in COLOR_NAMES], dtype=np.float64) * 255.0
"""(16, 3) albedo of each palette colour, in :data:`capmj.sim.palette.COLOR_NAMES` order."""

_D65 = np.array([0.95047, 1.0, 1.08883])
_RGB_TO_XYZ = np.array([[0.4124564, 0.3575761, 0.1804375],
                        [0.2126729, 0.7151522, 0.0721750],
                        [0.0193339, 0.1191920, 0.9503041]])


def _linear(c: np.ndarray) -> np.ndarray:
    """sRGB in [0, 1] to linear light (the sRGB transfer curve)."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


_LINEAR_U8 = _linear(np.arange(256) / 255.0)
"""Linear light of every 8-bit value: images are converted by lookup, 20x faster than the power."""


def srgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    """CIELAB (D65) of sRGB values in [0, 255], any leading shape (..., 3) -> (..., 3) float64."""
    a = np.asarray(rgb)
    if a.dtype == np.uint8 and a.ndim == 2 and len(a) > 4096:
        # Rendered images hold far fewer distinct colours than pixels: convert each once.
        packed = (a[:, 0].astype(np.int32) << 16) | (a[:, 1].astype(np.int32) << 8) | a[:, 2]
        distinct, where = np.unique(packed, return_inverse=True)
        rgb3 = np.stack([distinct >> 16, (distinct >> 8) & 255, distinct & 255], axis=1).astype(np.uint8)
        return _lab(rgb3)[where.ravel()]
    return _lab(a)


def _lab(a: np.ndarray) -> np.ndarray:
    lin = _LINEAR_U8[a] if a.dtype == np.uint8 else _linear(a.astype(np.float64) / 255.0)
    xyz = lin @ _RGB_TO_XYZ.T / _D65
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], axis=-1)


def camera_gain(table_pixels: np.ndarray) -> np.ndarray:
    """Per-channel gain (3,) of a camera from pixels known to show the table (N, 3).

    The median resists the few pixels of object edges that slip into the table selection; with
    no table pixel (an occluded view) the gain is the lighting's nominal 1.15.
    """
    px = np.asarray(table_pixels).reshape(-1, 3)
    if len(px) < 50:
        return np.full(3, 1.15)
    median = _median_u8(px) if px.dtype == np.uint8 else np.median(px.astype(np.float64), axis=0)
    return median / (np.array(TABLE_RGB) * 255.0)


def _median_u8(px: np.ndarray) -> np.ndarray:
    """``np.median(px, axis=0)`` of 8-bit pixels (N, 3) from their histograms: the same value
    (the middle one, or the mean of the two middle ones), without sorting 100 000 pixels."""
    n = len(px)
    out = np.empty(3)
    for ch in range(3):
        cum = np.cumsum(np.bincount(px[:, ch], minlength=256))
        lo, hi = np.searchsorted(cum, [(n - 1) // 2, n // 2], side="right")  # values of ranks (n-1)//2, n//2
        out[ch] = (float(lo) + float(hi)) / 2
    return out


@dataclass(frozen=True, eq=False)
class ColourModel:
    """The palette as seen by each camera (one row of predictions per camera gain)."""

    predicted_lab: np.ndarray
    """(n_cameras, 16, 3) CIELAB of ``clip(gain * albedo)`` per camera and palette colour."""

    @classmethod
    def from_gains(cls, gains: np.ndarray) -> ColourModel:
        g = np.asarray(gains, dtype=np.float64).reshape(-1, 1, 3)
        predicted = np.clip(g * PALETTE_RGB[None], 0.0, 255.0)
        return cls(predicted_lab=srgb_to_lab(predicted))

    def distances(self, lab: np.ndarray, camera: np.ndarray) -> np.ndarray:
        """ΔE (N, 16) from each pixel's Lab (N, 3), seen by camera index ``camera`` (N,), to every
        palette colour as that camera sees it."""
        pred = self.predicted_lab[np.asarray(camera, dtype=np.intp)]  # (N, 16, 3)
        return np.linalg.norm(np.asarray(lab)[:, None, :] - pred, axis=-1)

    def classify(self, lab: np.ndarray, camera: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(palette index (N,), ΔE to it (N,)) of the nearest predicted colour for every pixel."""
        d = self.distances(lab, camera)
        best = np.argmin(d, axis=1)
        return best, d[np.arange(len(best)), best]


__all__ = ["PALETTE_RGB", "TABLE_RGB", "ColourModel", "camera_gain", "srgb_to_lab"]
