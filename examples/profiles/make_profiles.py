"""Write the example wall profiles of this folder (x,y in mm, a header line).

- stenosis.csv: a vessel of radius 3 mm narrowed to 2.2 mm by a Gaussian bump
  centred at x = 14 mm (width 3 mm), sampled every 0.5 mm over 0..30 mm;
- ramp.csv: a wall rising linearly from 2.5 mm to 3.5 mm over 0..30 mm;
- step.csv: a smoothed step from 3.5 mm down to 2.5 mm at x = 15 mm
  (tanh, width 1.5 mm), every 0.5 mm.

Run ``python examples/profiles/make_profiles.py`` to regenerate them.
"""

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def write(name: str, x: np.ndarray, y: np.ndarray) -> None:
    rows = "\n".join(f"{a:.6g},{b:.10g}" for a, b in zip(x, y))
    (HERE / name).write_text("x_mm,y_mm\n" + rows + "\n")


if __name__ == "__main__":
    x = np.arange(0.0, 30.0 + 1e-9, 0.5)
    write("stenosis.csv", x, 3.0 - 0.8 * np.exp(-((x - 14.0) / 3.0) ** 2))
    write("ramp.csv", np.array([0.0, 30.0]), np.array([2.5, 3.5]))
    write("step.csv", x, 3.0 - 0.5 * np.tanh((x - 15.0) / 1.5))
