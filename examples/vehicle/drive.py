"""A vehicle's recorded motion, made by a simple vehicle model: the input of motion cueing (the
cueing FMU's `vehicle.file`, docs/guide/fmus.md). Three drives of a car on a flat road, each 20 s:

- drive.csv: cruising at 20 m/s, braking at 4 m/s^2 to 10 m/s, a lane change of 3.5 m, then a
  curve of 50 m radius, all with smooth (raised cosine) onsets;
- slalom.csv: cones passed at 15 m/s, a lateral acceleration of 4 m/s^2 at 0.25 Hz (faded in and
  out over 1 s) with its yaw rate;
- emergency_stop.csv: from cruise, braking at 8 m/s^2 from 2 s for 3 s (0.15 s onsets), then
  standing.

The occupant's head moves with the car's body, which neither pitches nor rolls: its specific force
is the car's acceleration plus gravity's reaction (x forward, y left, z up), its angular rate the
car's yaw rate. Each has its scene beside it (car_drive.toml, slalom.toml, emergency_stop.toml).

    python examples/vehicle/drive.py    # writes the three CSVs beside it
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


def slalom(rate: float = RATE, duration: float = DURATION) -> np.ndarray:
    """Cones passed at 15 m/s: a_y = 4 sin(2 pi 0.25 t) m/s^2 (faded in and out over 1 s), yaw rate
    a_y / v; rows of COLUMNS."""
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    fade = np.clip(t, 0.0, 1.0) * np.clip(t[-1] - t, 0.0, 1.0)
    lateral = 4.0 * np.sin(2 * np.pi * 0.25 * t) * fade
    zeros = np.zeros_like(t)
    return np.column_stack([t, zeros, lateral, np.full_like(t, G), zeros, zeros, lateral / 15.0])


def emergency_stop(rate: float = RATE, duration: float = DURATION) -> np.ndarray:
    """From cruise, braking at 8 m/s^2 from 2 s for 3 s (0.15 s onsets), then standing; rows of
    COLUMNS."""
    t = np.arange(0.0, duration + 0.5 / rate, 1.0 / rate)
    braking = -8.0 * np.clip((t - 2.0) / 0.15, 0, 1) * np.clip((5.0 - t) / 0.15, 0, 1)
    zeros = np.zeros_like(t)
    return np.column_stack([t, braking, zeros, np.full_like(t, G), zeros, zeros, zeros])


# each drive: its file, the function that makes it, what its first line says
DRIVES = {"drive.csv": (drive, "cruise, braking, lane change, curve"),
          "slalom.csv": (slalom, "a slalom at 15 m/s, 4 m/s^2 at 0.25 Hz"),
          "emergency_stop.csv": (emergency_stop, "an emergency stop from cruise, 8 m/s^2 for 3 s")}


def write(path: Path) -> Path:
    make, what = DRIVES[path.name]
    header = f"# A car's motion at the occupant's head: {what} (written by examples/vehicle/drive.py)\n" + \
        ",".join(COLUMNS)
    np.savetxt(path, make() + 0.0, delimiter=",", header=header, comments="", fmt="%.10g")  # + 0.0: no -0
    return path


if __name__ == "__main__":
    for name in DRIVES:
        print(f"written: {write(Path(__file__).with_name(name))}")
