"""The 2D structure tensor field of an image (Akl et al., ICIP 2014, §2, eqs. 1-5), in float64.

A tensor is stored as its three distinct components ``(xx, xy, yy)`` on the last axis. Axes
are the array's: x along columns (axis 1), y along rows (axis 0, downward); an angle is
measured from +x towards +y. The gradients are Gaussian-derivative convolutions (eq. 1) and
W is a Gaussian (eq. 3); each kernel is the sampled Gaussian cut at three sigma, the
derivative's scaled so that a unit ramp has unit gradient.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError

#: How an image is extended past its edges: mirrored (an exemplar, not toroidal) or wrapped (a
#: toroidal output), as :func:`numpy.pad` names them.
BOUNDARIES = ("reflect", "wrap")
#: The tensor's components on the last axis.
COMPONENTS = ("xx", "xy", "yy")


def gaussian_taps(sigma: float, derivative: bool = False) -> np.ndarray:
    """The sampled Gaussian of *sigma* on ``-r..r`` (r = ceil(3 sigma), at least 1), summing
    to 1; with *derivative*, ``-t g(t)`` scaled so that ``-sum t h(t) = 1``: convolved with a
    unit ramp it gives 1."""
    sigma = float(sigma)
    if not sigma > 0 or not math.isfinite(sigma):
        raise InputError(f"sigma={sigma!r} must be a positive number of pixels")
    r = max(1, math.ceil(3.0 * sigma))
    t = np.arange(-r, r + 1, dtype=np.float64)
    g = np.exp(-0.5 * (t / sigma) ** 2)
    if derivative:
        return -t * g / np.sum(t * t * g)
    return g / g.sum()


def check_radius(n: int, r: int) -> None:
    """Refuse a filter of radius *r* on a side of *n* pixels: one mirroring must reach past it."""
    if r >= n:
        raise InputError(f"a {n}-pixel side is too short for a filter of radius {r}: use smaller sigmas")


def convolve_axis(image: np.ndarray, taps: np.ndarray, axis: int, boundary: str, odd: bool = False) -> np.ndarray:
    """``sum_t taps[t] image[i - (t - r)]`` along *axis* (a convolution), the image extended by
    *boundary*. With *odd* taps (``taps[r + t] = -taps[r - t]``, a derivative) the sum is taken
    as ``sum_{t > 0} taps[r + t] (image[i - t] - image[i + t])``, so that a flat region's
    gradient is exactly 0, not rounding noise whose tensor would have any orientation."""
    r = taps.size // 2
    n = image.shape[axis]
    check_radius(n, r)
    pad = [(r, r) if a == axis else (0, 0) for a in range(image.ndim)]
    padded = np.pad(np.asarray(image, np.float64), pad, mode=boundary)
    out = np.zeros(image.shape, np.float64)
    at = np.arange(n) + r  # pixel i in the padded image

    def shifted(t: int) -> np.ndarray:
        return np.take(padded, at - t, axis=axis)

    if odd:
        for t in range(1, r + 1):
            out += taps[r + t] * (shifted(t) - shifted(-t))
        return out
    for j, w in enumerate(taps):  # tap j = offset t = j - r reads the pixel i - t
        out += w * shifted(j - r)
    return out


def _check(image: object, boundary: str) -> np.ndarray:
    img = np.asarray(image)
    if img.ndim != 2 or img.dtype.kind not in "biuf":
        raise InputError(f"the structure tensor takes a 2D grey image, got an array of shape {img.shape}")
    if boundary not in BOUNDARIES:
        raise InputError(f"boundary={boundary!r} must be one of {', '.join(map(repr, BOUNDARIES))}")
    img = img.astype(np.float64)
    if not np.isfinite(img).all():
        raise InputError("the image contains NaN or infinite values")
    return img


def structure_tensor(image: np.ndarray, grad_sigma: float = 1.0, window_sigma: float = 1.5,
                     boundary: str = "reflect") -> np.ndarray:
    """The structure tensor field of a grey *image* (eqs. 1-3).

    Parameters
    ----------
    image : array_like, (H, W)
        A grey image.
    grad_sigma : float
        Sigma of the Gaussian-derivative kernels G_x, G_y (eq. 1), pixels.
    window_sigma : float
        Sigma of the Gaussian W that smooths the gradient products (eq. 3), pixels. The
        default spans the 7 x 7 window the Urs thesis estimates orientations on (§6.3.2).
    boundary : {"reflect", "wrap"}
        How the image continues past its edges: mirrored (an exemplar) or wrapped (a toroidal
        output).

    Returns
    -------
    numpy.ndarray
        ``(H, W, 3)`` float64: ``S_xx, S_xy, S_yy`` at every pixel.
    """
    img = _check(image, boundary)
    g, dg = gaussian_taps(grad_sigma), gaussian_taps(grad_sigma, derivative=True)
    ix = convolve_axis(convolve_axis(img, dg, 1, boundary, odd=True), g, 0, boundary)
    iy = convolve_axis(convolve_axis(img, dg, 0, boundary, odd=True), g, 1, boundary)
    w = gaussian_taps(window_sigma)
    out = np.stack([ix * ix, ix * iy, iy * iy], axis=-1)
    return convolve_axis(convolve_axis(out, w, 1, boundary), w, 0, boundary)


def eigen(tensors: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(lambda1, lambda2, theta)`` of tensors ``(..., 3)``: the eigenvalues, largest first,
    and the angle of lambda1's eigenvector, ``0.5 atan2(2 S_xy, S_xx - S_yy)`` in
    ``(-pi/2, pi/2]``."""
    s = np.asarray(tensors, np.float64)
    xx, xy, yy = s[..., 0], s[..., 1], s[..., 2]
    half_trace = 0.5 * (xx + yy)
    radius = 0.5 * np.hypot(xx - yy, 2.0 * xy)
    return half_trace + radius, half_trace - radius, 0.5 * np.arctan2(2.0 * xy, xx - yy)


def coherence(tensors: np.ndarray) -> np.ndarray:
    """C = (lambda1 - lambda2) / (lambda1 + lambda2) (eq. 4), in [0, 1]; 0 where the tensor is 0
    (a flat region has no orientation)."""
    l1, l2, _ = eigen(tensors)
    trace = l1 + l2
    return np.where(trace > 0, (l1 - l2) / np.where(trace > 0, trace, 1.0), 0.0)


def orientation(tensors: np.ndarray) -> np.ndarray:
    """O (eq. 5): the angle of lambda1's eigenvector (the gradient's main direction; the
    stripes run at O + pi/2), radians in ``(-pi/2, pi/2]``."""
    return eigen(tensors)[2]


def log_tensor(tensors: np.ndarray, eps: float) -> np.ndarray:
    """The matrix logarithm of symmetric positive-definite tensors ``(..., 3)``, with each
    eigenvalue floored at *eps* (a structure tensor is only semi-definite: a straight edge
    or a flat region has a zero eigenvalue, whose logarithm would be minus infinity)."""
    l1, l2, theta = eigen(tensors)
    a, b = np.log(np.maximum(l1, eps)), np.log(np.maximum(l2, eps))
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([a * c * c + b * s * s, (a - b) * s * c, a * s * s + b * c * c], axis=-1)
