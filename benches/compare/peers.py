"""The methods dsc-seg is compared with, on 2D images and 3D volumes.

Every peer takes an image or volume with intensities in [0, 1] (float64) and
the number of phases K, and returns integer labels of the same shape. They
run with fixed, documented parameters: nothing is tuned per image.

* `multi_otsu`: the K-1 thresholds that maximise the between-class variance
  of the histogram (scikit-image `threshold_multiotsu`), applied voxel by voxel.
* `blur_multi_otsu`: the same on the image smoothed by a Gaussian of
  standard deviation 2 px: the cheapest strong baseline on noisy phantoms.
* `mbo`: the multiphase piecewise-constant Mumford-Shah (K-phase Chan-Vese,
  Potts) energy minimised by threshold dynamics (Merriman-Bence-Osher
  diffusion and thresholding, in the multiphase form of Esedoglu and Tsai,
  J. Comput. Phys. 211, 2006). One step diffuses each phase's indicator with a
  Gaussian of standard deviation s and gives every voxel the phase j that
  minimises (f - c_j)^2 + alpha (1 - G_s * chi_j), then updates the phase
  means c_j; it stops when no label changes (at most 100 steps). The length
  weight mu = 0.25 (image in [0, 1], lengths in pixels) becomes
  alpha = 2 mu sqrt(pi) / s, from Per(E) ~ sqrt(pi)/s * int (1 - chi) G_s * chi.
  Started from `multi_otsu` of the image smoothed with a Gaussian of 1 px.
  Works in any dimension.
* `chan_vese`: scikit-image's two-phase `chan_vese` with its defaults
  (mu = 0.25, tolerance 1e-3, at most 500 iterations, checkerboard start); 2D.
* `morph_chan_vese`: scikit-image's `morphological_chan_vese` (checkerboard
  start, lambda1 = lambda2 = 1; 150 iterations with smoothing 2 in 2D, 100
  iterations with smoothing 1 in 3D); two phases. Its phase with the larger
  mean is phase 1.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import ndimage


def multi_otsu(image: np.ndarray, phases: int) -> np.ndarray:
    from skimage.filters import threshold_multiotsu

    thresholds = threshold_multiotsu(image, classes=phases)
    return np.digitize(image, bins=thresholds)


def blur_multi_otsu(image: np.ndarray, phases: int, sigma: float = 2.0) -> np.ndarray:
    return multi_otsu(ndimage.gaussian_filter(image, sigma), phases)


def phase_means(image: np.ndarray, labels: np.ndarray, phases: int, previous: np.ndarray) -> np.ndarray:
    """Mean intensity of each phase; a phase without voxels keeps its previous mean."""
    sums = np.bincount(labels.ravel(), weights=image.ravel(), minlength=phases)
    counts = np.bincount(labels.ravel(), minlength=phases)
    return np.where(counts > 0, sums / np.maximum(counts, 1), previous)


def diffused_indicators(labels: np.ndarray, phases: int, sigma: float) -> np.ndarray:
    """G_s * chi_j for every phase j. The Gaussian (with replicated borders)
    keeps constants, so the indicators sum to one everywhere and the last one
    is one minus the others: K - 1 filters per step."""
    diffused = np.empty((phases,) + labels.shape)
    for j in range(phases - 1):
        ndimage.gaussian_filter((labels == j).astype(np.float64), sigma, mode="nearest", output=diffused[j])
    diffused[phases - 1] = 1.0 - diffused[: phases - 1].sum(axis=0)
    return diffused


def mbo(image: np.ndarray, phases: int, kernel_sigma: float = 2.0, mu: float = 0.25,
        max_steps: int = 100) -> np.ndarray:
    alpha = 2.0 * mu * math.sqrt(math.pi) / kernel_sigma
    labels = multi_otsu(ndimage.gaussian_filter(image, 1.0), phases)
    means = phase_means(image, labels, phases, np.zeros(phases))
    for _ in range(max_steps):
        shape = (phases,) + (1,) * image.ndim
        cost = (image[None] - means.reshape(shape)) ** 2
        cost += alpha * (1.0 - diffused_indicators(labels, phases, kernel_sigma))
        new_labels = np.argmin(cost, axis=0)
        unchanged = np.array_equal(new_labels, labels)
        labels = new_labels
        means = phase_means(image, labels, phases, means)
        if unchanged:
            break
    return labels


def chan_vese(image: np.ndarray, phases: int) -> np.ndarray:
    from skimage.segmentation import chan_vese as skimage_chan_vese

    return skimage_chan_vese(image, mu=0.25, lambda1=1.0, lambda2=1.0, tol=1e-3, max_num_iter=500,
                             dt=0.5, init_level_set="checkerboard").astype(np.int64)


def morph_chan_vese(image: np.ndarray, phases: int) -> np.ndarray:
    from skimage.segmentation import morphological_chan_vese

    iterations, smoothing = (150, 2) if image.ndim == 2 else (100, 1)
    labels = morphological_chan_vese(image, num_iter=iterations, init_level_set="checkerboard",
                                     smoothing=smoothing, lambda1=1, lambda2=1).astype(np.int64)
    if labels.any() and not labels.all() and image[labels == 1].mean() < image[labels == 0].mean():
        labels = 1 - labels
    return labels


# name -> (function, phase counts it handles, dimensions it handles)
PEERS = {
    "multi_otsu": (multi_otsu, range(2, 65), {2, 3}),
    "blur_multi_otsu": (blur_multi_otsu, range(2, 65), {2, 3}),
    "mbo": (mbo, range(2, 65), {2, 3}),
    "chan_vese": (chan_vese, {2}, {2}),
    "morph_chan_vese": (morph_chan_vese, {2}, {2, 3}),
}


def applicable(name: str, phases: int, ndim: int) -> bool:
    _, phase_counts, dims = PEERS[name]
    return phases in phase_counts and ndim in dims
