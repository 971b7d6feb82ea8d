#!/usr/bin/env python3
"""Expected HDR-FLIP figures for tests/flip.rs, computed by NVIDIA's own implementation.

    python3 -m venv /tmp/flipvenv && /tmp/flipvenv/bin/pip install flip-evaluator==1.7 numpy
    /tmp/flipvenv/bin/python tests/data/flip/make.py > tests/data/flip/expected.json

flip-evaluator 1.7 (PyPI, BSD-3-Clause; its C++ FLIP.h through nanobind) with numpy 2.4.
The images are made by formula in float64 and rounded to float32 (round to nearest); tests/flip.rs
makes the same bits in Rust, so the test needs no Python. Every pair is 32 x 24, linear RGB,
row 0 at the top, and scored as flip.evaluate(reference, test, "HDR") with FLIP's defaults
(ACES, automatic exposures, 67.02 pixels per degree) unless "ppd" is given.
"""

import json
import sys

import flip_evaluator as flip
import numpy as np

W, H = 32, 24


def lcg(seed):
    """Uniform floats in [0, 1): a 64-bit LCG (Knuth's MMIX constants), top 53 bits."""
    state = seed
    while True:
        state = (state * 6364136223846793005 + 1442695040888963407) % (1 << 64)
        yield (state >> 11) / float(1 << 53)


def spot(x, y, cx, cy, peak):
    """A bright spot without transcendental functions: peak / (1 + d^2)."""
    d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy)
    return peak / (1.0 + d2)


def gradient(x, y, cx, cy, peak, scale):
    s = spot(x, y, cx, cy, peak)
    return [
        scale * (0.05 + 0.9 * x / (W - 1)) + s,
        scale * (0.05 + 0.9 * y / (H - 1)) + s,
        scale * 0.3 + s,
    ]


def image(f):
    """f(x, y) -> [r, g, b] in float64, rounded to float32."""
    return np.array([[f(x, y) for x in range(W)] for y in range(H)], dtype=np.float64).astype(
        np.float32
    )


def noisy(base, seed, amount, floor):
    """base * (1 + amount (u - 0.5)) + floor u', per channel, u and u' drawn in that order,
    pixels in row order, channels r, g, b."""
    u = lcg(seed)
    out = np.empty_like(base)
    for y in range(H):
        for x in range(W):
            for c in range(3):
                a = next(u)
                b = next(u)
                out[y, x, c] = np.float32(float(base[y, x, c]) * (1.0 + amount * (a - 0.5)) + floor * b)
    return out


def cases():
    base = image(lambda x, y: gradient(x, y, 22, 7, 20.0, 1.0))
    shifted = image(lambda x, y: gradient(x, y, 20, 9, 20.0, 1.25))
    # More than half of the pixels black (the median luminance is 0: flip-evaluator 1.7's fix),
    # a spot of 500.
    dark = image(
        lambda x, y: [0.0, 0.0, 0.0] if x < 20 else gradient(x, y, 26, 12, 500.0, 0.02)
    )
    yield "identical", base, base.copy(), None
    yield "noise", base, noisy(base, 1, 0.4, 0.0), None
    yield "shifted", base, shifted, None
    yield "dark", dark, noisy(dark, 2, 0.6, 0.002), None
    yield "noise_ppd30", base, noisy(base, 1, 0.4, 0.0), 30.0


def main():
    out = {
        "generator": "tests/data/flip/make.py",
        "flip_evaluator": "1.7",
        "width": W,
        "height": H,
        "cases": [],
    }
    for name, ref, test, ppd in cases():
        params = {} if ppd is None else {"ppd": ppd}
        error_map, mean, used = flip.evaluate(
            np.ascontiguousarray(ref),
            np.ascontiguousarray(test),
            "HDR",
            applyMagma=False,
            computeMeanError=True,
            parameters=params,
        )
        error_map = np.asarray(error_map, dtype=np.float32).reshape(H, W)
        out["cases"].append(
            {
                "name": name,
                "ppd": ppd,
                "mean": float(mean),
                "start_exposure": float(used["startExposure"]),
                "stop_exposure": float(used["stopExposure"]),
                "exposures": int(used["numExposures"]),
                # Row-major, row 0 at the top; shortest decimal that reads back as the float32.
                "error_map": [
                    float(np.format_float_positional(v, unique=True)) for v in error_map.ravel()
                ],
            }
        )
    json.dump(out, sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
