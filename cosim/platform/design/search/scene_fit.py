"""A scene's reference motion as the specification: which value of one geometry parameter of its
platform carries it within the stroke and the joint limit (the validation's stroke study of Eq 35)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core import Core, mechanics_value
from ...scene import Scene
from ...run.alone import reference_motion


@dataclass
class SceneFit:
    """What a scene's reference motion asks of its platform's legs, and which value of one
    geometry parameter carries it within the stroke and the joint limit."""
    parameter: str
    values: np.ndarray          # the parameter's values tried
    shortest: np.ndarray        # per value, the shortest leg over the motion [m]
    longest: np.ndarray         # the longest [m]
    joint_angle: np.ndarray     # the largest joint angle [rad]
    stroke: tuple[float, float]  # the platform's [m]
    joint_limit: float          # [rad]

    @property
    def needed_stroke(self) -> np.ndarray:
        return self.longest - self.shortest

    @property
    def carries(self) -> np.ndarray:
        return (self.shortest >= self.stroke[0]) & (self.longest <= self.stroke[1]) & (self.joint_angle <= self.joint_limit)


def scene_fit(scene: Scene, parameter: str, values: np.ndarray, samples: int = 501) -> SceneFit:
    """The scene's reference motion (its trajectory FMU run alone: the one evaluation of its
    signals) on its own platform with `parameter` (a mechanics parameter, e.g.
    geometry.middle_leg_length) at each of `values`: every leg's range and the largest joint angle
    through the dynamics core, against the platform's stroke and joint limit. The motion is the
    reference poses; a parameter that moves the neutral moves the platform under them (the scene's
    offsets at "neutral" follow it)."""
    from ...run.compile import scene_values
    shortest, longest, angle = [], [], []
    base_values = scene_values(scene)[0]
    stroke = (float(mechanics_value(base_values, "limit.leg_length_min")),
              float(mechanics_value(base_values, "limit.leg_length_max")))
    joint_limit = float(mechanics_value(base_values, "limit.joint_angle"))
    core = Core(actuators=False, motors=False, friction=False)
    for value in values:
        changed = scene.changed({f'mechanics.parameters."{parameter}"': float(value)})
        _, poses, _ = reference_motion(changed, samples)
        core.use_start_values(scene_values(changed)[0])
        k = core.pose_kinematics(poses)
        shortest.append(k["length"].min())
        longest.append(k["length"].max())
        angle.append(max(k["upper_angle"].max(), k["lower_angle"].max()))
    return SceneFit(parameter, np.asarray(values, float), np.array(shortest), np.array(longest), np.array(angle),
                    stroke, joint_limit)
