"""Configuration design of a Stewart platform (Halder et al., Section V, for any platform family):
which platform carries a motion specification (`cosim design STUDY`, docs/guide/design.md).

A study (studies/*.toml; its keys in schema.py, read by reader.py into the Study of study.py)
sweeps two design values of a platform family and asks, at every grid point and for each motion
(motion.py: the basic motions, each DOF alone in the shortest time its limits allow, or a
recorded one), what the design map holds (map.py): the kinematic admissibility (Eqs 17-21:
actuated lengths against each actuator's running lengths, joint angles against the limit), the
dynamic admissibility (Fig 4: the paper's payload-only peak force, and the full inverse dynamics,
against the actuator's force less the margins) and the conditioning. Every pose goes through the
mechanics FMU's own dynamics core on the platform the FMU builds from the design (the one mapping,
cosim.platform.scene.parameter_sets), so the map and the co-simulation share one model.

Every row about a named design is of that design at exactly its values (map.at, map.along), not
of the grid's nearest point. Beyond the map: a design's workspace and distance to a singular pose (workspace.py), the design
with the largest worst-case margin (optimise.py), the Pareto front over several objectives with
the actuator (and a motor's screw lead) chosen from a catalogue together with the geometry, its
knee and extremes co-simulated (pareto.py, NSGA-II), a design confirmed by co-simulation through our
drives (confirm.py), a scene's motion as the specification (scene_fit.py); the figures
(figures.py), Section V's numbers beside ours (halder.py), and the study's answer as rows, a
summary and files (report.py).

Where the paper is loose (params/halder2013.toml says each choice): the disc's size "0.5mm" is read
as a 0.5 m radius, the design height as the disc's (z_q0, which gives the paper's neutral running
length 1647 mm at z = 1.4 m), Eq 1's even legs as (i - 2) pi/3, Section V's 100 kg payload with
Section VII's inertia scaled by mass (the study file says so), and the margins as the paper words
them (830 N less 7 % and 20 %: force_margins_mode "subtract"). Every summary lists these
assumptions first, each with what it changes at the chosen design (assumptions.py); every verdict
word comes from the study's thresholds (verdicts.py).
"""

from .search.map import DesignMap, design_map, parallel_map
from .spec.reader import load_study
from .answer.report import report_rows, summary, write
from .spec.schema import StudyError
from .spec.study import FAMILIES, Actuator, Study, platform_values

__all__ = ["Actuator", "DesignMap", "FAMILIES", "Study", "StudyError", "design_map", "load_study", "parallel_map",
           "platform_values", "report_rows", "summary", "write"]
