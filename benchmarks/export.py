"""The step an exported scene hands each other tool (cosim.platform.run.portable, `cosim export`):
per shipped scene, each tool's master (cosim.engine.tools) run in our engine on the exported system
(every FMU extrapolating the inputs its master holds, every connected input starting consistent) at
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
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.engine.tools import TOOL_MASTERS  # noqa: E402
from cosim.platform.run.portable import FLOOR, steps_text, tool_steps  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402

SCENES = sorted(p.stem for p in (ROOT / "scenes").glob("*.toml"))
DETAILED = "meng_eq35"  # the scene whose table is shown whole, as the export prints it


def main() -> None:
    tools = [m.tool for m in TOOL_MASTERS]
    summary = [f"| scene | its step | {' | '.join(tools)} | measured in |", "|---|---|" + "---|" * len(tools) + "---|"]
    detailed = []
    for name in SCENES:
        scene = load_scene(name)
        start = time.perf_counter()
        steps = tool_steps(scene)
        took = time.perf_counter() - start
        cells = [f"{s.step * 1e3:.4g} ms ({s.judgement.ratio:.2f})" if s.within else
                 f"none; closest {s.step * 1e3:.4g} ms ({s.judgement.ratio:.2f}, pose {s.judgement.pose_error:.1e})"
                 for s in steps]
        summary.append(f"| {name} | {scene.step * 1e3:g} ms | {' | '.join(cells)} | {took:.0f} s |")
        if name == DETAILED:
            text = steps_text(scene, steps)
            detailed = [f"**{name}**, the export's own table: {text[0]}", "", *text[1:]]
    lines = [f"Per shipped scene and tool, the step written (the largest within the tolerances, halving down "
             f"to 1/{FLOOR} of the scene's) and, in brackets, the efforts' worst window against its tolerance "
             f"there (at most 1: within); 'none': no step down to 1/{FLOOR} holds, the closest is written:", "",
             *summary, "", *detailed]
    publish("export", "python benchmarks/export.py", lines)


if __name__ == "__main__":
    main()
