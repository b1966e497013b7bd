"""Where a study's answer is found: the design map (map.py), a design's workspace (workspace.py),
the most robust design (optimise.py), the Pareto front (pareto.py), a design co-simulated
(confirm.py) and a scene's motion as the specification (scene_fit.py)."""
