"""A study's answer as the user reads it: rows, summary and files (report.py), figures
(figures.py), Section V beside ours (halder.py) and the assumptions where the paper is loose
(assumptions.py)."""
