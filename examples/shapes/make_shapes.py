"""Write the example shapes of this folder: what `lcpbench vision measure --json` gives for
photographs of an actuator (ℓ = 30 mm, EI = 40 N mm², w = 1.225e-3 N/mm, θ = 0.8 P + 10°),
and shapes.csv, the table `lcpbench fit --shapes` reads.

- free-60.json, free-100.json, free-140.json: free shapes at 60, 100, 140 kPa (their
  measured θ with 0.05° of noise; the centre line the circular arc);
- pressed-150.json, pressed-170.json: pressed in a 4 mm channel at 150 and 170 kPa, the
  model's centre line (N = 140, tol 1e-11) with 2 µm of noise per coordinate.

Synthetic (numpy default_rng(38)): the fit should give back about EI = 40 N mm² and the
line 0.8 P + 10°. Run ``python examples/shapes/make_shapes.py`` to regenerate them.
"""

import json
from pathlib import Path

import numpy as np

import lcpbench

HERE = Path(__file__).resolve().parent
SLOPE, INTERCEPT, EI, W, H, L = 0.8, 10.0, 40.0, 1.225e-3, 4.0, 30.0


def measured(c: np.ndarray, theta: float) -> dict:
    """The JSON of one section as `vision measure --json` writes it (the fields read)."""
    c = np.round(c, 5)
    return {"centerline_mm": c.tolist(), "pin_span_mm": float(c[-1, 0]),
            "sections": [{"theta_deg": theta, "start_mm": c[0].tolist(),
                          "end_mm": c[-1].tolist()}],
            "middle": {"theta_deg": theta, "index": 0}, "circle_fits": None}


def arc(theta: float, n: int = 41) -> np.ndarray:
    """A circular arc of angle θ (deg) and length ℓ between pins on y = 0."""
    t = np.radians(theta)
    r = L / t
    phi = np.linspace(-t / 2, t / 2, n)
    return np.column_stack([r * np.sin(phi) + r * np.sin(t / 2), r * (np.cos(phi) - np.cos(t / 2))])


if __name__ == "__main__":
    rng = np.random.default_rng(38)
    rows = []
    for P in (60, 100, 140):
        theta = SLOPE * P + INTERCEPT + 0.05 * rng.standard_normal()
        (HERE / f"free-{P}.json").write_text(json.dumps(measured(arc(theta), theta)))
        rows.append(f"free-{P}.json,{P},")
    for P in (150, 170):
        theta = SLOPE * P + INTERCEPT
        res = lcpbench.solve(lcpbench.ActuatorScene(theta=theta, height=H, links=140, EI=EI,
                                                    weight=W, channel=True), tol=1e-11)
        assert res.converged, res.reason
        c = np.column_stack([res.x, res.y]) + 0.002 * rng.standard_normal((res.x.size, 2))
        (HERE / f"pressed-{P}.json").write_text(json.dumps(measured(c, theta)))
        rows.append(f"pressed-{P}.json,{P},{H:g}")
    (HERE / "shapes.csv").write_text("shape,pressure_kpa,height_mm\n" + "\n".join(rows) + "\n")
