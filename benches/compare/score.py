"""Scoring of a label image against its ground truth, the same for every method.

Every distinct value of a label array is one label (so 0/255, 0..K-1 and
0/85/170/255 all work). Ground-truth phases and predicted labels are paired
one to one by the matching that maximises the overlap (Hungarian algorithm on
the confusion matrix); a phase left unmatched scores Dice 0. Works on 2D
images and 3D volumes alike.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment


def dense_labels(values: np.ndarray) -> np.ndarray:
    """Labels 0..L-1 in order of increasing value."""
    _, index = np.unique(values, return_inverse=True)
    return index.reshape(values.shape)


def confusion(truth: np.ndarray, pred: np.ndarray) -> np.ndarray:
    """Counts of (truth phase, predicted label) pairs; rows are truth phases."""
    truth, pred = dense_labels(truth), dense_labels(pred)
    rows, cols = int(truth.max()) + 1, int(pred.max()) + 1
    pairs = truth.ravel().astype(np.int64) * cols + pred.ravel()
    return np.bincount(pairs, minlength=rows * cols).reshape(rows, cols)


def score(truth: np.ndarray, pred: np.ndarray) -> dict:
    """Dice per truth phase, their mean and the pixel accuracy after matching."""
    if truth.shape != pred.shape:
        raise ValueError(f"ground truth is {truth.shape} but the prediction is {pred.shape}")
    counts = confusion(truth, pred)
    truth_idx, pred_idx = linear_sum_assignment(counts, maximize=True)
    truth_sizes, pred_sizes = counts.sum(axis=1), counts.sum(axis=0)
    dice = np.zeros(counts.shape[0])
    for t, p in zip(truth_idx, pred_idx):
        dice[t] = 2.0 * counts[t, p] / (truth_sizes[t] + pred_sizes[p])
    return {
        "dice": [float(d) for d in dice],
        "mean_dice": float(dice.mean()),
        "accuracy": float(counts[truth_idx, pred_idx].sum() / truth.size),
    }
