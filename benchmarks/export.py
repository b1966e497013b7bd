"""The step an exported scene hands each other tool (cosim.platform.run.portable, `cosim export`):
per shipped scene of each drive kind, each tool's master (cosim.engine.tools) run in our engine at
the scene's step and each half of it down to a 64th, over the scene's probe, against its converged
run; the largest step within the shipped scenes' tolerances, or the closest. Written as block
`export` of docs/benchmarks.md, quoted by docs/guide/engine.md.

    python benchmarks/export.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.platform.run.portable import steps_text, tool_steps  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402

SCENES = ("meng_eq35", "sumnu_case_1")


def main() -> None:
    lines = []
    for name in SCENES:
        scene = load_scene(name)
        start = time.perf_counter()
        steps = tool_steps(scene)
        took = time.perf_counter() - start
        text = steps_text(scene, steps)
        lines += [f"**{name}** (its own step {scene.step * 1e3:g} ms; measured in {took:.0f} s): {text[0]}", "",
                  *text[1:], ""]
    publish("export", "python benchmarks/export.py", lines[:-1])


if __name__ == "__main__":
    main()
