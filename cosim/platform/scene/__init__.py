"""A scene: one run of the platform, as the user writes it (a TOML file), read and checked into a
`Scene` (cosim.platform.scene.reader); its signals as the trajectory FMU's parameters (signals),
a drive FMU of the user's own (drive_fmu) and the project's parameter sets (parameter_sets)."""

from .reader import (Pulse, Ramp, Scene, SceneError, Signal, Sine, Step, load_scene, scene_settings, shipped,
                     shipped_scenes)

__all__ = ["Pulse", "Ramp", "Scene", "SceneError", "Signal", "Sine", "Step", "load_scene", "scene_settings",
           "shipped", "shipped_scenes"]
