"""A vehicle's recorded motion, made by a simple vehicle model: the input of motion cueing (the
cueing FMU's `vehicle.file`, docs/guide/fmus.md). A car on a flat road: cruising at 20 m/s, braking
at 4 m/s^2 to 10 m/s, a lane change of 3.5 m, then a curve of 50 m radius, all with smooth (raised
cosine) onsets. The occupant's head moves with the car's body, which neither pitches nor rolls: its
specific force is the car's acceleration plus gravity's reaction (x forward, y left, z up), its
angular rate the car's yaw rate.

    python examples/vehicle/drive.py    # writes examples/vehicle/drive.csv
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

G = 9.81  # the platform's gravity (params/meng2010.toml): one gravity for the vehicle and every FMU
RATE = 100.0  # samples per second
DURATION = 20.0
COLUMNS = ("time", "specific_force.x", "specific_force.y", "specific_force.z", "angular_rate.x", "angular_rate.y",
           "angular_rate.z")


def smooth_window(t: np.ndarray, start: float, end: float, rise: float) -> np.ndarray:
    """1 between start and end, 0 outside, with raised-cosine edges of `rise` seconds."""
    up = np.clip((t - start) / rise, 0.0, 1.0)
    down = np.clip((end - t) / rise, 0.0, 1.0)
    return np.minimum(0.5 - 0.5 * np.cos(np.pi * up), 0.5 - 0.5 * np.cos(np.pi * down))


def drive(rate: float = RATE, duration: float = DURATION) -> np.ndarray:
    """The motion as rows of COLUMNS."""
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    braking = -4.0 * smooth_window(t, 2.0, 4.5, 0.3)
    speed = 20.0 + np.concatenate([[0.0], np.cumsum(0.5 * (braking[1:] + braking[:-1]) / rate)])  # trapezoidal
    lane = np.where((t >= 6.0) & (t <= 9.0), 3.5 * 2 * np.pi / 9.0 * np.sin(2 * np.pi * (t - 6.0) / 3.0), 0.0)
    curve_rate = speed / 50.0 * smooth_window(t, 11.0, 17.0, 1.0)  # 50 m radius
    yaw_rate = lane / speed + curve_rate
    lateral = lane + speed * curve_rate  # a_y = v psi' in the curve
    zeros = np.zeros_like(t)
    return np.column_stack([t, braking, lateral, np.full_like(t, G), zeros, zeros, yaw_rate])


def write(path: Path) -> Path:
    rows = drive()
    header = ("# A car's motion at the occupant's head: cruise, braking, lane change, curve (written by "
              "examples/vehicle/drive.py)\n" + ",".join(COLUMNS))
    np.savetxt(path, rows + 0.0, delimiter=",", header=header, comments="", fmt="%.10g")  # + 0.0: no -0
    return path


if __name__ == "__main__":
    print(f"written: {write(Path(__file__).with_name('drive.csv'))}")
