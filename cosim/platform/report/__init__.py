"""What a finished run shows: plots like the papers' figures (plots), the interactive HTML report
(html), the platform in 3D (view3d) and tables of numbers beside the papers' (rows)."""
