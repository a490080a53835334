"""Times SciPy's spline fits on the problem sizes of crates/gdt-bridge/benches/splines.rs.

    python3 -m venv /tmp/scipy-venv && /tmp/scipy-venv/bin/pip install scipy numpy
    /tmp/scipy-venv/bin/python docs/comparisons/scipy_splines.py

Prints the median over repeats of each call (seconds per call), as criterion reports medians.
The samples and knots are the same as the Rust bench's: x = 0..n, y = 10 sin(x/10) plus a fixed
wiggle, clamped cubic knots with uniform interior knots; unit weights.
"""

import timeit

import numpy as np
import scipy
from scipy.interpolate import make_lsq_spline, make_smoothing_spline


def samples(n):
    x = np.arange(n, dtype=float)
    y = 10.0 * np.sin(x / 10.0) + 0.5 * np.modf(np.sin(x * 12.9898))[0]
    return x, y


def knots(x, interior):
    a, b = x[0], x[-1]
    inner = a + (b - a) * np.arange(1, interior + 1) / (interior + 1)
    return np.r_[[a] * 4, inner, [b] * 4]


def median_time(stmt, number):
    runs = timeit.repeat(stmt, number=number, repeat=15)
    return float(np.median(runs)) / number


def main():
    print(f"numpy {np.__version__}, scipy {scipy.__version__}")
    for n, interior in [(180, 4), (10_000, 100)]:
        x, y = samples(n)
        w = np.ones(n)
        t = knots(x, interior)
        s = median_time(lambda: make_lsq_spline(x, y, t, k=3, w=w), 200 if n < 1000 else 20)
        print(f"make_lsq_spline n={n} coefficients={interior + 4}: {s * 1e6:.1f} µs")
    x, y = samples(180)
    s = median_time(lambda: make_smoothing_spline(x, y), 50)
    print(f"make_smoothing_spline(lam=None, GCV) n=180: {s * 1e6:.1f} µs")


if __name__ == "__main__":
    main()
