"""The platform application: the Stewart platform of the papers on the generic engine.

Its rooms, each importing only from those above it (docs/guide/layout.md):
- `ports`, `core`: what the platform is, the ports of ../shared/INTERFACES.md and the dynamics
  core the mechanics FMU is built from;
- `scene`: the files a user writes about one run (a scene, its signals, drives of the user's
  own, the parameter sets) read into typed objects;
- `report`: what a finished run shows (plots, the HTML report, the 3D view, tables of numbers);
- `run`: a scene wired into a system, its drives tuned, run, judged and swept;
- `advise`, `design`, `validation`: the questions asked of many runs and poses.
"""
