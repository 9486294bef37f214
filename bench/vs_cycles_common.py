"""Figures shared by bench/vs_cycles.py and its --check (bench/vs_cycles_check.py): the mean
difference of two images per channel and how the scripts print per-channel values."""
import numpy as np


def mean_diff_pct(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per channel, 100 (mean(a) / mean(b) - 1)."""
    return 100.0 * (a.astype(np.float64).mean(axis=(0, 1)) / b.astype(np.float64).mean(axis=(0, 1)) - 1.0)


def _fmt(v) -> str:
    return ",".join(f"{x:.4g}" for x in v)
