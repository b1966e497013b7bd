"""The motion envelope's margins, measured (cosim.platform.realtime.margins, docs/guide/realtime.md).

For every shipped platform and drive kind (a shipped scene of each: its platform, drives and
[live] limits, no load), the guarded reference steps far outside the envelope on every axis at
once, into each leg's top and bottom (the axes signed as that leg's length grows or shrinks with
each), so that it reaches the edge with every axis at its top [live] rate and acceleration and
brakes there; the platform lags it. Reported per scene: the shipped margins (limit.stroke_margin,
limit.joint_margin), the largest excess of the platform's legs over the reference's usable stroke
and of its joints over the reference's usable tilt, the margins that excess asks for (1.5 times
it, rounded up to a millimetre and a tenth of a degree), and the platform's legs and largest tilt
against the stroke and the joints' limit. A shipped margin below what its excess asks for is
flagged.

    python benchmarks/envelope.py [--write]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.platform.realtime import Envelope  # noqa: E402
from cosim.platform.realtime.margins import margin_needed, measure  # noqa: E402
from cosim.platform.run.compile import scene_values  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402

SCENES = ("meng_eq35", "meng_eq35_linear", "sumnu_case_1", "sumnu_case_1_pmsm")
MM, TENTH_DEGREE = 1e-3, math.radians(0.1)


def main() -> None:
    rows = ["| scene (platform, drives) | shipped margins: stroke / joints | platform past the reference's edge: "
            "stroke / joints (most) | margins that asks for | platform's legs [m] / largest tilt [deg] | "
            "within the stroke and joints' limit |", "|---|---|---|---|---|---|"]
    for name in SCENES:
        scene = load_scene(name)
        envelope = Envelope.of(scene_values(scene)[0])
        probes = measure(scene, duration=4.0)
        assert all(p.reached for p in probes), [p.direction for p in probes if not p.reached]
        stroke = max(p.stroke_excess for p in probes)
        joints = max(p.joint_excess for p in probes)
        low, high = min(p.legs[0] for p in probes), max(p.legs[1] for p in probes)
        tilt = max(p.tilt for p in probes)
        needs = (margin_needed(stroke, MM) if stroke > 0 else 0.0, margin_needed(joints, TENTH_DEGREE) if joints > 0 else 0.0)
        short = needs[0] > envelope.margin + 1e-12 or needs[1] > envelope.joint_margin + 1e-12
        inside = envelope.stroke[0] <= low and high <= envelope.stroke[1] and tilt <= envelope.joint_angle
        rows.append(f"| {name} ({scene.parameter_set}, {scene.drive}) | {1e3 * envelope.margin:g} mm / "
                    f"{math.degrees(envelope.joint_margin):.2g} deg | {1e3 * stroke:.2f} mm / "
                    f"{math.degrees(joints):.3f} deg | {1e3 * needs[0]:g} mm / {math.degrees(needs[1]):.1f} deg"
                    f"{' (more than shipped)' if short else ''} | {low:.4f}-{high:.4f} / {math.degrees(tilt):.2f} | "
                    f"{'yes' if inside else 'NO'} |")
        print(rows[-1], flush=True)
    publish("envelope", "python benchmarks/envelope.py", rows)


if __name__ == "__main__":
    main()
